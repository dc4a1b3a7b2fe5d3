#!/usr/bin/env bash
# Installs, with apt, the Debian packages fragg_map needs that are not installed yet: ROS 1
# from Debian's own packages (../shared/ROS.md), the libraries of the core and the CLI, the
# test and format tools. Installs nothing (and runs no apt-get update) when all are present.
# Runs as root (CI) or through sudo. Extra packages on the command line are handled the same
# way (e.g. `rviz xvfb` to look at the map in rviz without a screen).
# When another apt or dpkg holds its lock (common on a fresh machine: unattended upgrades), it
# waits for it, at most FRAGG_APT_LOCK_WAIT_S seconds (default 600), saying so once.
# Usage: bash scripts/install_deps.sh [--dry-run] [--demo] [EXTRA_PACKAGE...]
# --demo: only what scripts/demo.sh builds and runs (tests off): none of test_packages below
# (about 35 MB of the download: clang-format brings LLVM).
# Fuzzing and the clang sanitizer builds (optional, not needed by CI: scripts/fuzz.sh,
# scripts/sanitize.sh): bash scripts/install_deps.sh clang-14 libfuzzer-14-dev libomp-14-dev
# (Sourced, it only defines its functions: test/scripts/ tests the lock wait that way.)
set -euo pipefail

packages=(
  # the toolchain: g++ is nvcc's host compiler and the default C++ compiler (a machine with only
  # clang fails at CMake's CUDA check: "cannot execute 'cc1plus'")
  g++ make cmake
  # ROS 1 (the ROS.md list)
  ros-core-dev catkin libnodeletlib-dev libnodelet-dev libnodeletlib-tools rosbash
  libtf2-ros-dev libtf2-eigen-dev libtf2-sensor-msgs-dev libpcl-ros-dev libpcl-conversions-dev
  libpcl-dev libeigen3-dev libvisualization-msgs-dev libnav-msgs-dev libstd-srvs-dev
  libsensor-msgs-dev librosbag-dev python3-rosbag
  python3-roslaunch python3-rosservice python3-rosnode python3-rostopic ros-message-generation
  python3-geometry-msgs python3-sensor-msgs python3-visualization-msgs python3-tf2-msgs
  python3-std-srvs python3-nav-msgs liboctomap-dev
  # ~check_collision takes a shape_msgs/Mesh
  libshape-msgs-dev python3-shape-msgs
  # ~set_parameters (octomap_server's dynamic_reconfigure names; rostest client)
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  # core, CLI
  libcli11-dev nlohmann-json3-dev libpng-dev libfmt-dev zlib1g-dev bzip2
  # page stores (optional in CMake): SQLite (the default), LMDB, zstd for the records; zstd
  # also packs the .fgm block chunks (zlib without it); the zstd tool reads them in rostests
  libsqlite3-dev liblmdb-dev libzstd-dev zstd
)
# The tests, the format check, the benchmarks and the docs' figures: everything but the demo
# (whose build has the tests off) needs them; --demo leaves them out.
test_packages=(
  libgtest-dev libgmock-dev librostest-dev python3-rostest libbenchmark-dev clang-format
  octomap-tools
  # collision checking: FCL as an oracle in the tests (optional in CMake)
  libfcl-dev
  # docs: the benchmark figure (scripts/plot_fig5b.sh)
  gnuplot-nox
  # the peer benchmark: glm's headers, copied into .device/ for OHM's build (scripts/ohm_peer.sh)
  libglm-dev
)

# apt's and dpkg's lock files (apt and dpkg hold them with fcntl locks while they run).
FRAGG_APT_LOCK_FILES="${FRAGG_APT_LOCK_FILES:-/var/lib/dpkg/lock-frontend /var/lib/dpkg/lock \
/var/lib/apt/lists/lock /var/cache/apt/archives/lock}"

# Whether a process holds a lock on one of FRAGG_APT_LOCK_FILES: looks the files up in
# /proc/locks (POSIX and flock locks, any user's, no root needed, nothing taken). Files are
# matched by inode and device; by inode alone where the file's device has major 0 (overlay or
# tmpfs), whose device /proc/locks may name differently.
apt_lock_held() {
  local f dev ino major minor
  for f in $FRAGG_APT_LOCK_FILES; do
    [ -e "$f" ] || continue
    read -r major minor ino < <(stat -L -c '%Hd %Ld %i' "$f") || continue
    if [ "$major" = 0 ]; then dev='[0-9a-f]+:[0-9a-f]+'
    else dev="$(printf '%02x:%02x' "$major" "$minor")"; fi
    grep -Eq "[[:space:]]${dev}:${ino}[[:space:]]" /proc/locks && return 0
  done
  return 1
}

# Waits while apt_lock_held, at most FRAGG_APT_LOCK_WAIT_S seconds (polling every
# FRAGG_APT_LOCK_POLL_S, default 2), printing one line when it starts waiting. Returns 1 if the
# lock is still held at the end.
wait_for_apt_lock() {
  local limit="${FRAGG_APT_LOCK_WAIT_S:-600}" poll="${FRAGG_APT_LOCK_POLL_S:-2}" start=$SECONDS
  apt_lock_held || return 0
  echo "install_deps: another apt or dpkg holds its lock; waiting for it (at most ${limit} s)"
  while apt_lock_held; do
    if [ $((SECONDS - start)) -ge "$limit" ]; then
      echo "install_deps: the apt/dpkg lock is still held after ${limit} s; try again later" >&2
      return 1
    fi
    sleep "$poll"
  done
  echo "install_deps: the lock is free after $((SECONDS - start)) s"
}

# What the first build will take, scaled from measured figures: ~11 min at -j2 on a fresh
# 2-core machine without a GPU, CUDA kernels for every architecture included (issue 16); the
# demo's (--demo: its targets only, unity batches, no tests, no CUDA without a GPU) about 360
# CPU seconds (issue 38: 492 CPU s for its whole first run, 128 of them the demo steps).
print_build_estimate() {
  local cores demo="${1:-0}"
  cores="$(nproc 2>/dev/null || echo 2)"
  [ "$cores" -ge 1 ] 2>/dev/null || cores=2
  if [ "$demo" -eq 1 ]; then
    echo "install_deps: next, the demo's first build: about $(((6 + cores - 1) / cores)) min" \
      "on $cores core(s) (about 6 CPU minutes: its targets only, in unity batches)"
    return
  fi
  echo "install_deps: next, the first build: about $(((11 * 2 + cores - 1) / cores)) min on" \
    "$cores core(s) (measured: 11 min on 2 cores with CUDA for every architecture; the demo" \
    "skips CUDA without a GPU)"
}

# The packages apt would install for `missing` (dependencies included, no recommends) and
# their download size, from apt's own plan (needs the package lists).
print_install_plan() {
  local count mib
  count="$(apt-get -s -o Debug::NoLocking=1 install --no-install-recommends "$@" 2>/dev/null |
    grep -c '^Inst ' || true)"
  mib="$(apt-get -qq -o Debug::NoLocking=1 install --no-install-recommends --print-uris "$@" \
    2>/dev/null | awk '{s += $3} END {printf "%.1f", s / 1048576}' || true)"
  echo "install_deps: apt will install ${count:-?} package(s) (the $# named and their" \
    "dependencies, no recommends), ${mib:-?} MiB to download"
}

main() {
  dry_run=0
  demo=0
  extra=()
  for arg in "$@"; do
    case "$arg" in
      --dry-run) dry_run=1 ;;
      --demo) demo=1 ;;
      -*) echo "install_deps: unknown option $arg (usage: [--dry-run] [--demo] [EXTRA_PACKAGE...])" >&2; exit 2 ;;
      *) extra+=("$arg") ;;
    esac
  done
  [ "$demo" -eq 1 ] || packages+=("${test_packages[@]}")
  packages+=("${extra[@]+"${extra[@]}"}")

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
    print_install_plan "${missing[@]}"
    print_build_estimate "$demo"
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
  wait_for_apt_lock
  # apt's own wait covers a lock taken again between the check and the call.
  lock_timeout=(-o "DPkg::Lock::Timeout=${FRAGG_APT_LOCK_WAIT_S:-600}")
  "${as_root[@]}" apt-get "${lock_timeout[@]}" update
  print_install_plan "${missing[@]}"
  print_build_estimate "$demo"
  echo "install_deps: installing (no recommends): ${missing[*]}"
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get "${lock_timeout[@]}" install -y --no-install-recommends "${missing[@]}"
  echo "install_deps: installed ${missing[*]}"
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then main "$@"; fi
