#!/usr/bin/env bash
# On the GPU machine (plain CMake, no ROS): build, run the `gpu` tests, optionally under
# compute-sanitizer, and the benchmark. Data and liboctomap come staged under .device/
# (real/ copied from ../shared/data/real, octomap/ from ../shared/tools/stage-octomap.sh, store/
# from scripts/stage_store.sh).
# Usage: bash scripts/device_check.sh [tests] [sanitize] [workloads LIST] [collision [MAP]]
#        [frontiers]
#        [bench ARGS...] | [ohm ARGS...]
# (workloads go to .device/workloads; bench ARGS are fragg_map_bench's; collision runs
# fragg_map_collision_bench on MAP, default .device/w1.fgm, built from .device/workloads/
# w1_lidar360 at 5 cm, 30 m, when missing: run `workloads w1` before it; ohm builds the peer
# mapper OHM from .device/ohm-src and runs fragg_map_ohm_bench with ARGS: scripts/ohm_peer.sh).
# Logs go to $OUT when set (the device tool brings them back).
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${OUT:-$root/out/device}"
mkdir -p "$out"
build="$root/build-device"
# The page stores (SQLite, zstd, LMDB) come staged under .device/store (scripts/stage_store.sh).
store_args=()
if [ -d "$root/.device/store" ]; then
  store_args=(-DSTORE_ROOT="$root/.device/store")
  export LD_LIBRARY_PATH="$root/.device/store/lib:${LD_LIBRARY_PATH:-}"
fi
cmake -S "$root" -B "$build" -DFRAGG_WITH_ROS=OFF -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CUDA_ARCHITECTURES=90 -DFRAGG_REAL_DATA="$root/.device/real" \
  -DOCTOMAP_ROOT="$root/.device/octomap" "${store_args[@]}" >"$out/cmake.log" 2>&1 || { tail -30 "$out/cmake.log"; exit 1; }
grep -E "page store|SQLite3 or zstd" "$out/cmake.log"
cmake --build "$build" -j "$(nproc)" >"$out/build.log" 2>&1 || { grep -E "error" "$out/build.log" | head -30; exit 1; }
echo "build ok"
export LD_LIBRARY_PATH="$root/.device/octomap/lib:${LD_LIBRARY_PATH:-}"
status=0
while [ $# -gt 0 ]; do
  case "$1" in
    tests)
      (cd "$build" && ctest -L gpu --output-on-failure -j1 >"$out/gpu_tests.log" 2>&1) || status=1
      grep -E "^\[gpu\]|tests passed|Failed|FAILED|Skipped" "$out/gpu_tests.log" | head -40
      "$build/test/fragg_gpu_test" >"$out/gpu_test_verbose.log" 2>&1 || status=1
      grep -E "^\[gpu\]|PASSED|FAILED|Failure|Expected|Which is|actual" "$out/gpu_test_verbose.log" | head -60
      shift ;;
    sanitize)
      # memcheck (with leak check): every gpu test binary, whole. racecheck (slower): the ray
      # kernels (insertion, prepare, host readers, removal on real scans) and the device block
      # cache's tests. A finding or a failed test sets the exit status.
      for bin in fragg_gpu_test fragg_gpu_cache_test fragg_gpu_paging_test \
        fragg_gpu_collision_test fragg_gpu_frontier_test fragg_gpu_submap_test; do
        if [ ! -x "$build/test/$bin" ]; then echo "compute-sanitizer: $bin not built: skipped"; continue; fi
        compute-sanitizer --tool memcheck --leak-check full --error-exitcode 9 \
          "$build/test/$bin" >"$out/sanitizer_memcheck_$bin.log" 2>&1
        rc=$?
        echo "compute-sanitizer memcheck $bin: exit $rc"; tail -3 "$out/sanitizer_memcheck_$bin.log"
        [ "$rc" -eq 0 ] || status=1
      done
      compute-sanitizer --tool racecheck --error-exitcode 9 \
        "$build/test/fragg_gpu_test" \
        --gtest_filter='*PrepareKernel*:*HostReaders*:*TinyPool*:*VelodynePair*:*PoseCorrectionIsByteIdenticalOnRealScans*:*RangeNoise*' \
        >"$out/sanitizer_racecheck.log" 2>&1
      rc=$?
      echo "compute-sanitizer racecheck (ray kernels): exit $rc"; tail -3 "$out/sanitizer_racecheck.log"
      [ "$rc" -eq 0 ] || status=1
      compute-sanitizer --tool racecheck --error-exitcode 9 "$build/test/fragg_gpu_cache_test" \
        >"$out/sanitizer_racecheck_cache.log" 2>&1
      rc=$?
      echo "compute-sanitizer racecheck (cache tests): exit $rc"
      tail -3 "$out/sanitizer_racecheck_cache.log"
      [ "$rc" -eq 0 ] || status=1
      shift ;;
    workloads)
      bash "$root/scripts/make_workloads.sh" --out "$root/.device/workloads" --only "$2" \
        --sim "$build/bin/fragg_map_sim" 2>&1 | grep -v "^  " | tail -8
      shift 2 ;;
    collision)
      map="$root/.device/w1.fgm"
      if [ $# -gt 1 ] && [ -f "$2" ]; then map="$2"; shift; fi
      if [ ! -f "$map" ]; then
        "$build/bin/fragg_map" build "$root/.device/workloads/w1_lidar360" -o "$map" \
          --resolution 0.05 --max-range 30 --backend cuda >"$out/w1_build.log" 2>&1 ||
          { tail -5 "$out/w1_build.log"; status=1; shift; continue; }
      fi
      "$build/bin/fragg_map_collision_bench" --map "$map" --backends cpu cuda \
        --json "$out/collision_bench.json" 2>&1 | tee "$out/collision_bench.log" || status=1
      shift ;;
    frontiers)
      # Issue 14's figures: W1 at 5 cm, 30 m on each backend (needs `workloads w1` first).
      for backend in cuda cpu; do
        "$build/bin/fragg_map_frontier_bench" --workloads "$root/.device/workloads" \
          --backend "$backend" --json "$out/frontier_bench_$backend.json" 2>&1 |
          tee "$out/frontier_bench_$backend.log" || status=1
      done
      shift ;;
    ohm)
      shift
      bash "$root/scripts/ohm_peer.sh" ohm bench "$@" || status=1
      break ;;
    bench)
      shift
      "$build/bin/fragg_map_bench" "$@" 2>&1 | tee "$out/bench.log" | tail -40
      break ;;
    *) echo "unknown step $1"; exit 2 ;;
  esac
done
exit $status
