#!/usr/bin/env bash
# Installs, with apt, the Debian packages fragg_map needs that are not installed yet: ROS 1
# from Debian's own packages (../shared/ROS.md), the libraries of the core and the CLI, the
# test and format tools. Installs nothing (and runs no apt-get update) when all are present.
# Runs as root (CI) or through sudo. Extra packages on the command line are handled the same
# way (e.g. `rviz xvfb` to look at the map in rviz without a screen).
# Usage: bash scripts/install_deps.sh [--dry-run] [EXTRA_PACKAGE...]
set -euo pipefail

packages=(
  # ROS 1 (the ROS.md list)
  ros-core-dev catkin libnodeletlib-dev libnodelet-dev libnodeletlib-tools rosbash
  libtf2-ros-dev libtf2-eigen-dev libtf2-sensor-msgs-dev libpcl-ros-dev libpcl-conversions-dev
  libpcl-dev libeigen3-dev libvisualization-msgs-dev libnav-msgs-dev libstd-srvs-dev
  libsensor-msgs-dev librosbag-dev librostest-dev python3-rostest python3-rosbag
  python3-roslaunch python3-rosservice python3-rosnode python3-rostopic ros-message-generation
  python3-geometry-msgs python3-sensor-msgs python3-visualization-msgs python3-tf2-msgs
  python3-std-srvs python3-nav-msgs liboctomap-dev libgtest-dev
  # core, CLI, benchmark, tests, format check
  libcli11-dev nlohmann-json3-dev libpng-dev libfmt-dev libbenchmark-dev zlib1g-dev
  clang-format octomap-tools libgmock-dev bzip2
  # page stores (optional in CMake): SQLite (the default), LMDB, zstd for the records
  libsqlite3-dev liblmdb-dev libzstd-dev
  # collision checking: FCL as an oracle in the tests (optional in CMake)
  libfcl-dev
  # docs: the benchmark figure (scripts/plot_fig5b.sh)
  gnuplot-nox
)

dry_run=0
for arg in "$@"; do
  case "$arg" in
    --dry-run) dry_run=1 ;;
    -*) echo "install_deps: unknown option $arg (usage: [--dry-run] [EXTRA_PACKAGE...])" >&2; exit 2 ;;
    *) packages+=("$arg") ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  status="$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)"
  [ "$status" = "installed" ] || missing+=("$p")
done

if [ "${#missing[@]}" -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages are installed"
  exit 0
fi

echo "install_deps: missing ${#missing[@]} package(s): ${missing[*]}"
if [ "$dry_run" -eq 1 ]; then
  exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
  as_root=()
elif command -v sudo >/dev/null 2>&1; then
  as_root=(sudo)
else
  echo "install_deps: not root and no sudo: install these as root: ${missing[*]}" >&2
  exit 1
fi

export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive \
  apt-get install -y --no-install-recommends "${missing[@]}"
echo "install_deps: installed ${missing[*]}"
