#!/usr/bin/env bash
# The peer GPU mapper OHM (csiro-robotics/ohm, CUDA GpuMap) beside fragg on the same GPU
# (issue 17 item 3). OHM's sources are never committed: a copy lies under .device/ohm-src
# (git-ignored), Debian's glm headers under .device/glm.
#
# Steps (each one a word on the command line, run in order):
#   prepare [SRC]  here, with internet: SRC is an OHM git directory (the `fetch` tool's
#                  snapshot) or a source tree; exports it to .device/ohm-src (no SRC: keeps the
#                  copy there), adds the missing `#include <utility>` lines (idempotent), copies
#                  /usr/include/glm (libglm-dev) to .device/glm.
#   ohm            GPU machine: configures OHM (the issue's flags, CUDA arch 90), builds the
#                  libraries GpuMap needs (not OHM's tools) and installs them into .device/ohm,
#                  then packs .device/ohm into $OUT/ohm-install.tar.gz so that a later call can
#                  carry it; does nothing when .device/ohm is there already (carried).
#   bench [ARGS]   GPU machine: builds fragg_map_ohm_bench with -DOHM_ROOT=.device/ohm (in
#                  build-device, as scripts/device_check.sh), generates W1/W2 into
#                  .device/workloads when missing, runs the bench on W1 30 m, W1 50 m and W2
#                  5 cm; ARGS go to the bench (e.g. --workload-scans 50). Logs and JSON to $OUT.
# Environment: OHM_BUILD_DIR, OHM_PREFIX override .device/ohm-build and .device/ohm.
# Usage: bash scripts/ohm_peer.sh prepare /work/.mirror/csiro-robotics+ohm/repo
#        bash scripts/ohm_peer.sh ohm bench          (GPU machine, one call if time allows)
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${OUT:-$root/out/device}"
src="$root/.device/ohm-src"
glm="$root/.device/glm"
prefix="${OHM_PREFIX:-$root/.device/ohm}"
obuild="${OHM_BUILD_DIR:-$root/.device/ohm-build}"
jobs="$(nproc)"
mkdir -p "$out"

# The sources that use std::exchange without including <utility> (g++ 13's libstdc++ no
# longer brings it in transitively). The line goes before the file's first #include.
ohm_utility_fixes() {
  local f n=0
  for f in gputil/cuda/gpuQueue.cpp gputil/cuda/gpuPinnedBuffer.cpp gputil/cl/gpuQueue.cpp \
    gputil/cl/gpuPinnedBuffer.cpp ohm/MapChunk.cpp ohm/Voxel.h ohm/VoxelBuffer.cpp \
    ohmutil/PlyPointStream.cpp; do
    [ -f "$src/$f" ] || { echo "ohm_peer: $src/$f missing (another OHM version?)" >&2; return 1; }
    grep -q '^#include <utility>' "$src/$f" && continue
    sed -i '0,/^#include/s//#include <utility>\n#include/' "$src/$f"
    grep -q '^#include <utility>' "$src/$f" || { echo "ohm_peer: cannot patch $f" >&2; return 1; }
    n=$((n + 1))
  done
  # Any other user of std::exchange without the include would fail to compile: say so now.
  local missing
  missing=$(cd "$src" && grep -rl 'std::exchange' --include='*.h' --include='*.cpp' . |
    xargs grep -L '^#include <utility>' || true)
  [ -z "$missing" ] || { echo "ohm_peer: std::exchange without <utility> in: $missing" >&2; return 1; }
  echo "ohm_peer: <utility> added to $n files"
}

step_prepare() {
  local from="${1:-}"
  if [ -n "$from" ]; then
    rm -rf "$src" && mkdir -p "$src"
    if git --git-dir="$from" rev-parse HEAD >/dev/null 2>&1; then
      git --git-dir="$from" archive HEAD | tar -x -C "$src" || return 1
      git --git-dir="$from" rev-parse HEAD >"$src/.ohm_commit"
    elif [ -f "$from/CMakeLists.txt" ] && [ -d "$from/ohmgpu" ]; then
      cp -r "$from/." "$src/"
    else
      echo "ohm_peer: $from is neither an OHM git directory nor an OHM source tree" >&2
      return 1
    fi
  fi
  [ -f "$src/ohmgpu/GpuMap.h" ] || { echo "ohm_peer: no OHM sources in $src" >&2; return 1; }
  ohm_utility_fixes || return 1
  if [ ! -f "$glm/glm/glm.hpp" ]; then
    [ -f /usr/include/glm/glm.hpp ] ||
      { echo "ohm_peer: install libglm-dev first (scripts/install_deps.sh)" >&2; return 1; }
    mkdir -p "$glm" && cp -r /usr/include/glm "$glm/"
  fi
  du -sh "$src" "$glm"
}

step_ohm() {
  if [ -f "$prefix/lib/libohmcuda.a" ] && [ -f "$prefix/include/ohm/ohmgpu/GpuMap.h" ]; then
    echo "ohm_peer: OHM already installed in $prefix (carried or built before): not rebuilt"
    return 0
  fi
  [ -f "$src/ohmgpu/GpuMap.h" ] || { echo "ohm_peer: no $src (run prepare here first)" >&2; return 1; }
  [ -f "$glm/glm/glm.hpp" ] || { echo "ohm_peer: no $glm/glm (run prepare)" >&2; return 1; }
  # OHM needs zlib (its map serialisation); say it plainly when the machine lacks it.
  if [ ! -f /usr/include/zlib.h ]; then
    echo "ohm_peer: zlib.h not found (zlib1g-dev): OHM cannot be built on this machine" >&2
    return 1
  fi
  ohm_utility_fixes || return 1
  local t0=$SECONDS
  # OHM_CUDA_ARCHITECTURES, not only CMAKE_CUDA_ARCHITECTURES: OHM's own default list starts at
  # sm_50, which CUDA 13 no longer compiles.
  cmake -S "$src" -B "$obuild" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$prefix" \
    -DGLM_INCLUDE_DIRS="$glm" \
    -DOHM_FEATURE_CUDA=ON -DOHM_FEATURE_OPENCL=OFF -DOHM_FEATURE_PDAL=OFF \
    -DOHM_FEATURE_TEST=OFF -DOHM_FEATURE_HEIGHTMAP=ON -DOHM_FEATURE_HEIGHTMAP_IMAGE=OFF \
    -DOHM_FEATURE_THREADS=OFF -DOHM_FEATURE_EIGEN=OFF -DOHM_BUILD_DOXYGEN=OFF \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DOHM_CUDA_ARCHITECTURES=90 >"$out/ohm_cmake.log" 2>&1 ||
    { tail -30 "$out/ohm_cmake.log"; return 1; }
  # Only the libraries GpuMap needs (ohmcuda pulls ohm, gputilcuda, ohmutil, logutil), not
  # OHM's tools; each one's headers and library installed by its own install script.
  cmake --build "$obuild" -j "$jobs" --target ohmcuda >"$out/ohm_build.log" 2>&1 ||
    { grep -E "error|Error" "$out/ohm_build.log" | head -30; return 1; }
  local d
  for d in logutil ohmutil gputil ohm ohmgpu; do
    cmake -DCMAKE_INSTALL_PREFIX="$prefix" -P "$obuild/$d/cmake_install.cmake" \
      >>"$out/ohm_install.log" 2>&1 || { tail -20 "$out/ohm_install.log"; return 1; }
  done
  echo "ohm_peer: OHM libraries built and installed in $((SECONDS - t0)) s"
  du -sh "$prefix"
  # Brought back by the device tool: unpack into .device/ and carry .device/ohm next time.
  tar -C "$(dirname "$prefix")" -czf "$out/ohm-install.tar.gz" "$(basename "$prefix")" &&
    du -h "$out/ohm-install.tar.gz"
}

step_bench() {
  [ -d "$prefix" ] || { echo "ohm_peer: no $prefix (run the ohm step, or carry .device/ohm)" >&2; return 1; }
  local build="$root/build-device"
  cmake -S "$root" -B "$build" -DFRAGG_WITH_ROS=OFF -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DOCTOMAP_ROOT="$root/.device/octomap" \
    -DOHM_ROOT="$prefix" -DOHM_GLM_INCLUDE_DIR="$glm" >"$out/bench_cmake.log" 2>&1 ||
    { tail -30 "$out/bench_cmake.log"; return 1; }
  grep -E "OHM" "$out/bench_cmake.log"
  cmake --build "$build" -j "$jobs" --target fragg_map_ohm_bench fragg_map_sim \
    >"$out/bench_build.log" 2>&1 || { grep -E "error" "$out/bench_build.log" | head -30; return 1; }
  local wl="$root/.device/workloads"
  # Workloads missing on this machine are generated (deterministic: the same files as elsewhere).
  local need=()
  [ -d "$wl/w1_lidar360" ] || need+=(w1)
  [ -d "$wl/w2_depth" ] || need+=(w2)
  if [ ${#need[@]} -gt 0 ]; then
    local list
    list=$(IFS=,; echo "${need[*]}")
    bash "$root/scripts/make_workloads.sh" --out "$wl" --only "$list" \
      --sim "$build/bin/fragg_map_sim" 2>&1 | grep -v "^  " | tail -4
  fi
  export LD_LIBRARY_PATH="$prefix/lib:$root/.device/octomap/lib:${LD_LIBRARY_PATH:-}"
  "$build/bin/fragg_map_ohm_bench" --workloads "$wl" \
    --json "$out/ohm_bench.json" "$@" 2>&1 | tee "$out/ohm_bench.log"
  return "${PIPESTATUS[0]}"
}

[ $# -gt 0 ] || { sed -n "2,/^set -uo/p" "$0" | sed "\$d"; exit 2; }
case "$1" in
  prepare) shift; step_prepare "$@"; exit $? ;;
esac
while [ $# -gt 0 ]; do
  case "$1" in
    ohm) step_ohm || exit 1; shift ;;
    bench) shift; step_bench "$@"; exit $? ;;
    *) echo "ohm_peer: unknown step $1 (prepare, ohm, bench)" >&2; exit 2 ;;
  esac
done
