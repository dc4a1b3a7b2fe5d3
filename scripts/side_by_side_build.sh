#!/usr/bin/env bash
# Builds the real octomap_server (octomap_mapping kinetic-devel), octomap_ros and octomap_msgs
# from source in a scratch catkin workspace, for scripts/side_by_side.sh. Nothing of it enters
# the repository: the workspace lies under out/side_by_side/ (git-ignored).
#   bash scripts/side_by_side_build.sh [--mirror DIR] [--jobs N]
# --mirror DIR: local copies DIR/OctoMap+<name>/repo (git directories) instead of cloning
# github.com/OctoMap/<name>. Checked out: octomap_mapping efa61ca (kinetic-devel, 0.6.8, the
# one issue 38 compared), octomap_ros and octomap_msgs melodic-devel heads.
set -euo pipefail
source "$(dirname "$0")/common.sh"

MIRROR=""
JOBS=1
while [ $# -gt 0 ]; do
  case "$1" in
    --mirror) MIRROR="${2:?--mirror needs a folder}"; shift 2 ;;
    --jobs) JOBS="${2:?--jobs needs a number}"; shift 2 ;;
    *) echo "side_by_side_build.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done

SCRATCH="$FRAGG_REPO/out/side_by_side"
WS="$SCRATCH/octomap_ws"
mkdir -p "$WS/src"

# name ref: the source tree of github.com/OctoMap/<name> at <ref>, into $WS/src/<name>.
checkout() {
  local name="$1" ref="$2" dest="$WS/src/$1"
  [ -d "$dest" ] && return 0
  local git_dir
  if [ -n "$MIRROR" ] && [ -d "$MIRROR/OctoMap+$name/repo" ]; then
    git_dir="$MIRROR/OctoMap+$name/repo"
  else
    git clone --quiet --bare "https://github.com/OctoMap/$name" "$SCRATCH/$name.git"
    git_dir="$SCRATCH/$name.git"
  fi
  mkdir -p "$dest.tmp"
  git --git-dir="$git_dir" archive "$ref" | tar -x -C "$dest.tmp"
  mv "$dest.tmp" "$dest"
  echo "$name: $(git --git-dir="$git_dir" rev-parse --short "$ref")"
}
checkout octomap_mapping efa61ca
checkout octomap_ros melodic-devel
checkout octomap_msgs melodic-devel
# Only octomap_server of octomap_mapping (the metapackage needs nothing).
rm -rf "$WS/src/octomap_mapping/octomap_mapping"

cd "$WS"
catkin_make -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
  -DPython3_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=OFF -j"$JOBS" \
  octomap_server_node octomap_saver octomap_msgs_generate_messages >"$SCRATCH/build.log" 2>&1 || {
  tail -30 "$SCRATCH/build.log" >&2
  exit 1
}
echo "octomap_server built in $WS (log $SCRATCH/build.log)"
