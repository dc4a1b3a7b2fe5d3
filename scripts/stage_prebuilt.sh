#!/usr/bin/env bash
# Builds the GPU machine's programs here (x86-64, nvcc for sm_90, no ROS) and stages them,
# stripped, under DEST (default .device/pre) so that a device call only runs them: no build
# in the call, whose minutes are scarce. DEST/head holds this tree's programs, DEST/base the
# benchmark of BASE when given (git archive BASE, built with tests off), DEST/lib the shared
# libraries Ubuntu's image lacks (fmt; FCL and libccd). liboctomap and the page stores come from
# .device/octomap and .device/store (../shared/tools/stage-octomap.sh, scripts/stage_store.sh),
# carried beside DEST. The gpu tests that read ../shared/data/real find it at FRAGG_REAL_DATA's
# path as compiled: pass --real-data PATH as it will be on the device (it is not known here),
# or run only tests that need none. Builds go to BUILD (default /tmp/fragg_prebuilt),
# incremental.
# Usage: bash scripts/stage_prebuilt.sh [--base COMMIT] [--dest DIR] [--build DIR]
#          [--jobs N] [--real-data PATH] [TARGET...]
# (default targets: fragg_map_bench fragg_map_frontier_bench fragg_map_collision_bench
#  fragg_map_sim fragg_map_cli (the program fragg_map) fragg_gpu_frontier_test
#  fragg_gpu_state_masks_test)
# On the device: scripts/device_prebuilt.sh.
set -euo pipefail
top=$(git rev-parse --show-toplevel)
dest=$top/.device/pre
build=/tmp/fragg_prebuilt
base=""
jobs=$(nproc)
real=/nonexistent/real
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --base) base=$2; shift 2 ;;
    --dest) dest=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --real-data) real=$2; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) targets+=("$1"); shift ;;
  esac
done
[ ${#targets[@]} -eq 0 ] && targets=(fragg_map_bench fragg_map_frontier_bench fragg_map_collision_bench
  fragg_map_sim fragg_map_cli fragg_gpu_frontier_test fragg_gpu_state_masks_test)
for d in octomap store; do
  [ -d "$top/.device/$d" ] || { echo "missing .device/$d: stage it first (see this script's header)" >&2; exit 1; }
done
cfg=(-DFRAGG_WITH_ROS=OFF -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_ARCHITECTURES=90-real
  -DOCTOMAP_ROOT="$top/.device/octomap" -DSTORE_ROOT="$top/.device/store")
mkdir -p "$build"
rm -rf "$dest" && mkdir -p "$dest/head" "$dest/lib"
grep -qs "^CMAKE_HOME_DIRECTORY:INTERNAL=$top\$" "$build/head/CMakeCache.txt" || rm -rf "$build/head"
cmake -S "$top" -B "$build/head" "${cfg[@]}" -DFRAGG_REAL_DATA="$real" >"$build/head.cmake.log"
cmake --build "$build/head" -j "$jobs" --target "${targets[@]}" >"$build/head.build.log" 2>&1 ||
  { grep -m10 -E "error" "$build/head.build.log"; exit 1; }
# Programs land in bin/, tests in their own folders: find each target's executable.
for t in "${targets[@]}"; do
  name=$t
  [ "$t" = fragg_map_cli ] && name=fragg_map  # the CLI target's OUTPUT_NAME
  f=$(find "$build/head" -name "$name" -type f -perm -u+x | head -1)
  [ -n "$f" ] || { echo "no executable for $t" >&2; exit 1; }
  cp "$f" "$dest/head/"
done
if [ -n "$base" ]; then
  # The base's sources are unpacked again only for another commit (same files, same times:
  # the base's build stays incremental).
  base_commit=$(git -C "$top" rev-parse "$base^{commit}")
  mkdir -p "$dest/base"
  if [ "$(cat "$build/base-src.commit" 2>/dev/null)" != "$base_commit" ]; then
    rm -rf "$build/base-src" && mkdir -p "$build/base-src"
    git -C "$top" archive "$base_commit" | tar -x -C "$build/base-src"
    echo "$base_commit" >"$build/base-src.commit"
  fi
  # A build folder configured from another source tree is made again.
  grep -qs "^CMAKE_HOME_DIRECTORY:INTERNAL=$build/base-src\$" "$build/base/CMakeCache.txt" ||
    rm -rf "$build/base"
  cmake -S "$build/base-src" -B "$build/base" "${cfg[@]}" -DFRAGG_BUILD_TESTS=OFF >"$build/base.cmake.log"
  cmake --build "$build/base" -j "$jobs" --target fragg_map_bench >"$build/base.build.log" 2>&1 ||
    { grep -m10 -E "error" "$build/base.build.log"; exit 1; }
  cp "$build/base/bin/fragg_map_bench" "$dest/base/"
  echo "$base_commit" >"$dest/base/COMMIT"
fi
strip "$dest"/head/*
if [ -n "$base" ]; then strip "$dest/base/fragg_map_bench"; fi
# Debian libraries the GPU machine's image lacks: fmt 9; FCL and libccd for the collision bench
# (liboctomap comes with .device/octomap).
cp -a /lib/x86_64-linux-gnu/libfmt.so.9* "$dest/lib/"
cp -L /usr/lib/x86_64-linux-gnu/libfcl.so.0.7 /lib/x86_64-linux-gnu/libccd.so.2 "$dest/lib/"
git -C "$top" rev-parse HEAD >"$dest/head/COMMIT"
git -C "$top" diff --quiet || echo "(with uncommitted changes)" >>"$dest/head/COMMIT"
echo "staged in $dest ($(du -sh "$dest" | cut -f1); carry it with .device/octomap and .device/store):"
ls "$dest"/head "$dest"/base 2>/dev/null | tr '\n' ' '
echo
