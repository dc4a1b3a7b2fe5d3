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
# w1_lidar360 at 5 cm, 30 m, when missing: run `workloads w1` before it; its arguments from
# FRAGG_COLLISION_ARGS when set; ohm builds the peer
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
# FRAGG_BUILD_TARGETS (space-separated) builds only those targets, e.g. the gpu tests.
targets=()
[ -n "${FRAGG_BUILD_TARGETS:-}" ] && read -r -a targets <<<"--target $FRAGG_BUILD_TARGETS"
cmake --build "$build" -j "$(nproc)" "${targets[@]}" >"$out/build.log" 2>&1 || { grep -E "error" "$out/build.log" | head -30; exit 1; }
echo "build ok"
export LD_LIBRARY_PATH="$root/.device/octomap/lib:${LD_LIBRARY_PATH:-}"
status=0
while [ $# -gt 0 ]; do
  case "$1" in
    tests)
      (cd "$build" && ctest -L gpu --output-on-failure -j1 >"$out/gpu_tests.log" 2>&1) || status=1
      grep -E "^\[gpu\]|tests passed|Failed|FAILED|Skipped" "$out/gpu_tests.log" | head -40
      # ctest counts a skipped test as passed ("100% tests passed"): the verdict per entry,
      # passed and skipped apart (a test that skips itself ran nothing on the device).
      echo "gpu tests: $(grep -cE 'Test +#[0-9]+: .* Passed' "$out/gpu_tests.log") passed," \
        "$(grep -cE 'Test +#[0-9]+: .*\*\*\*Skipped' "$out/gpu_tests.log") skipped," \
        "$(grep -cE 'Test +#[0-9]+: .*\*\*\*(Failed|Exception|Timeout|Not Run)' "$out/gpu_tests.log") failed" \
        "of $(grep -cE 'Test +#[0-9]+: ' "$out/gpu_tests.log") ctest entries"
      "$build/test/fragg_gpu_test" >"$out/gpu_test_verbose.log" 2>&1 || status=1
      grep -E "^\[gpu\]|PASSED|FAILED|Failure|Expected|Which is|actual" "$out/gpu_test_verbose.log" | head -60
      shift ;;
    sanitize)
      # Every test case of every gpu test binary, each in its own compute-sanitizer process:
      # memcheck (with leak check) and racecheck, FRAGG_SANITIZE_JOBS at a time (default 12,
      # the slow cases first), each stopped after FRAGG_SANITIZE_TIMEOUT s (default 420). A finding, a failed test or
      # a timeout sets the exit status. One line per case in sanitizer_summary.txt, the logs in
      # sanitizer_logs.tar.gz.
      sdir="$(mktemp -d)"
      : >"$sdir/jobs"
      for bin in fragg_gpu_test fragg_gpu_cache_test fragg_gpu_paging_test \
        fragg_gpu_collision_test fragg_gpu_frontier_test fragg_gpu_submap_test \
        fragg_gpu_state_masks_test fragg_gpu_dynamic_test; do
        if [ ! -x "$build/test/$bin" ]; then echo "compute-sanitizer: $bin not built: skipped"; continue; fi
        "$build/test/$bin" --gtest_list_tests | awk '
          /^[^ ]/ { suite = $1; next }
          /^  / { print suite $1 }' | while read -r case_name; do
          for tool in memcheck racecheck; do echo "$tool $bin $case_name" >>"$sdir/jobs"; done
        done
      done
      # The slow cases first, so that they do not start last.
      slow='SimulatedW1|RangeNoise|SaturatedBlock|EveryShape|PosesPrepared|CudaTrackerEqualsCpu|Synthetic|Paging\.|PathsMatch'
      export build sdir slow
      sanitize_one() {
        local tool="$1" bin="$2" case_name="$3" extra=() start rc note=""
        [ "$tool" = memcheck ] && extra=(--leak-check full)
        # racecheck of the slow cases: only their first FRAGG_RACECHECK_SLOW_LAUNCHES kernel
        # launches (0: all); their kernels are the ones the smaller cases check whole.
        if [ "$tool" = racecheck ] && [ "${FRAGG_RACECHECK_SLOW_LAUNCHES:-0}" != 0 ] &&
          [[ "$case_name" =~ $slow ]]; then
          extra=(--launch-count "$FRAGG_RACECHECK_SLOW_LAUNCHES")
          note="first $FRAGG_RACECHECK_SLOW_LAUNCHES launches"
        fi
        local tag="${tool}_${bin}_${case_name//[^A-Za-z0-9_.-]/_}"
        local log="$sdir/$tag.log"
        mkdir -p "$sdir/tmp/$tag"
        start=$(date +%s)
        FRAGG_TEST_TMP="$sdir/tmp/$tag" timeout "${FRAGG_SANITIZE_TIMEOUT:-420}" \
          compute-sanitizer --tool "$tool" "${extra[@]}" --error-exitcode 9 \
          "$build/test/$bin" --gtest_filter="$case_name" >"$log" 2>&1
        rc=$?
        rm -rf "$sdir/tmp/$tag"
        local verdict=clean
        [ "$rc" -eq 124 ] && verdict=timeout
        [ "$rc" -ne 0 ] && [ "$rc" -ne 124 ] && verdict="exit $rc"
        grep -q "\[  SKIPPED \]" "$log" && [ "$rc" -eq 0 ] && verdict="clean (skipped)"
        printf '%s %s %s %ss %s%s | %s\n' "$tool" "$bin" "$case_name" "$(( $(date +%s) - start ))" \
          "$verdict" "${note:+ ($note)}" "$(grep -E "ERROR SUMMARY|RACECHECK SUMMARY|LEAK SUMMARY" "$log" | tr '\n' ' ')"
      }
      export -f sanitize_one
      # FRAGG_SANITIZE_FILTER (a regex over "TOOL BINARY CASE") runs a subset.
      grep -E "${FRAGG_SANITIZE_FILTER:-.}" "$sdir/jobs" >"$sdir/jobs.kept"
      mv "$sdir/jobs.kept" "$sdir/jobs"
      { grep -E "$slow" "$sdir/jobs"; grep -vE "$slow" "$sdir/jobs"; } >"$sdir/jobs.ordered"
      njobs=$(wc -l <"$sdir/jobs")
      echo "compute-sanitizer: $njobs runs ($(grep -c ^memcheck "$sdir/jobs") cases x memcheck, racecheck)"
      # Each line is appended as its run ends, so that a cut-off call still brings them back.
      : >"$out/sanitizer_summary.txt"
      xargs -P "${FRAGG_SANITIZE_JOBS:-12}" -L 1 bash -c 'sanitize_one "$@" >>"$0"' \
        "$out/sanitizer_summary.txt" <"$sdir/jobs.ordered"
      sort -o "$out/sanitizer_summary.txt" "$out/sanitizer_summary.txt"
      tar -czf "$out/sanitizer_logs.tar.gz" -C "$sdir" . 2>/dev/null
      grep -qv " clean" "$out/sanitizer_summary.txt" &&
        { echo "compute-sanitizer: NOT clean:"; grep -v " clean" "$out/sanitizer_summary.txt"; status=1; }
      echo "compute-sanitizer: $(grep -c " clean" "$out/sanitizer_summary.txt") of $njobs runs clean" \
        "($(grep -c "clean (skipped)" "$out/sanitizer_summary.txt") of them skipped by the test)"
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
      # FRAGG_COLLISION_ARGS (word-split) replaces the default arguments "--backends cpu cuda",
      # e.g. "--backends cuda --fcl-poses 0 --pose-prep both".
      read -r -a collision_args <<<"${FRAGG_COLLISION_ARGS:---backends cpu cuda}"
      "$build/bin/fragg_map_collision_bench" --map "$map" "${collision_args[@]}" \
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
