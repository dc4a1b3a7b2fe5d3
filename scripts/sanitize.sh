#!/usr/bin/env bash
# Sanitizer runs (issue 18), without ROS and without CUDA:
#   asan: an ASan + UBSan build of the core, io, interop, geometry, planning, loop-closure,
#         sub-map and CLI tests and the fuzz corpus replay, each test binary run whole
#         (LeakSanitizer on; a UBSan finding stops the test).
#   replay: the asan build of the fuzz corpus replay alone (fragg_fuzz_corpus_test: every
#         committed corpus input through its reader), the short run CI does (scripts/test.sh).
#   tsan: a TSan build of the concurrency tests: the map lock (readers, writers, a query
#         answered during a long insertion, no half-inserted scan seen) and the server's
#         ROS-free parts (the drop-oldest cloud queue between subscriber and insertion thread,
#         the marker throttle, the timing statistics).
# Usage: bash scripts/sanitize.sh [asan] [replay] [tsan]   (asan and tsan when none is named)
# Environment: CXX (compiler, default clang++ when found, else g++), FRAGG_ASAN_BUILD and
# FRAGG_TSAN_BUILD (build folders, default build-asan, build-tsan; a FRAGG_FUZZ=ON build folder
# may serve as the asan one: its libraries carry ASan + UBSan too), FRAGG_SANITIZE_JOBS (2),
# FRAGG_SANITIZE_CMAKE_ARGS (more configure arguments, e.g. on the GPU machine's host:
# "-DFRAGG_REAL_DATA=$PWD/.device/real -DOCTOMAP_ROOT=$PWD/.device/octomap").
# The GPU tests under compute-sanitizer: scripts/device_check.sh sanitize (GPU machine).
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
jobs="${FRAGG_SANITIZE_JOBS:-2}"
cxx="${CXX:-$(command -v clang++ || command -v g++)}"
steps=("$@")
[ ${#steps[@]} -gt 0 ] || steps=(asan tsan)

asan_tests=(fragg_core_test fragg_cache_test io_point_file_test io_dataset_test
  io_scan_graph_octomap_test interop_test interop_octomap_test interop_cli_test cli_build_test
  fragg_geometry_test fragg_planning_test cli_collide_test fragg_loop_closure_test
  cli_correct_test fragg_submap_test cli_submap_test fragg_fuzz_corpus_test)

# configure BUILD SANITIZER: a plain CMake build (no ROS, no CUDA) with that sanitizer, -O1 and
# NDEBUG as the Release builds (fragg_map has no assert(); liboctomap's header templates print
# debug lines on stderr without NDEBUG, which the CLI tests forbid), unless
# BUILD is already configured (a fuzz build counts as an address one).
configure() {
  local build="$1" sanitizer="$2" cache="$1/CMakeCache.txt"
  if [ -f "$cache" ] && { grep -q "^FRAGG_SANITIZE:STRING=$sanitizer$" "$cache" ||
    { [ "$sanitizer" = address ] && grep -q "^FRAGG_FUZZ:BOOL=ON$" "$cache"; }; }; then
    return 0
  fi
  mkdir -p "$build"
  cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER="$cxx" -DFRAGG_SANITIZE="$sanitizer" \
    -DFRAGG_WITH_ROS=OFF -DFRAGG_WITH_CUDA=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -DNDEBUG" ${FRAGG_SANITIZE_CMAKE_ARGS:-} \
    >"$build/sanitize-cmake.log" 2>&1 ||
    { tail -20 "$build/sanitize-cmake.log"; return 1; }
}

# run_test LOG BINARY [ARGS...]: runs one test binary; prints its verdict.
run_test() {
  local log="$1" bin="$2"
  shift 2
  if [ ! -x "$bin" ]; then
    echo "  $(basename "$bin"): not built here (optional dependency missing): skipped"
    return 0
  fi
  if "$bin" "$@" >"$log" 2>&1; then
    echo "  $(basename "$bin"): clean ($(grep -Eo '[0-9]+ tests? from [0-9]+ test (suite|case)s? ran' "$log" | tail -1))"
  else
    echo "  $(basename "$bin"): FAILED (log $log)"
    grep -E "ERROR: (Address|Leak|Thread)Sanitizer|runtime error:|WARNING: ThreadSanitizer|\[  FAILED  \]|SUMMARY" "$log" | head -8
    return 1
  fi
}

status=0
for step in "${steps[@]}"; do
  case "$step" in
    asan)
      build="${FRAGG_ASAN_BUILD:-$root/build-asan}"
      configure "$build" address || { status=1; continue; }
      # Targets this configuration has (some need liboctomap).
      targets=(fragg_map_cli)  # the CLI (output name fragg_map) the cli tests run
      for t in "${asan_tests[@]}"; do
        grep -q "^$t:" <(cmake --build "$build" --target help 2>/dev/null | sed 's/^\.\.\. //;s/$/:/') &&
          targets+=("$t")
      done
      echo "sanitize: asan build ($build): ${targets[*]}"
      cmake --build "$build" -j "$jobs" --target "${targets[@]}" >"$build/sanitize-build.log" 2>&1 ||
        { grep -E "error" "$build/sanitize-build.log" | head -20; status=1; continue; }
      export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1"
      export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
      for t in "${asan_tests[@]}"; do
        run_test "$build/$t.sanitize.log" "$build/test/$t" || status=1
      done
      ;;
    replay)
      build="${FRAGG_ASAN_BUILD:-$root/build-asan}"
      configure "$build" address || { status=1; continue; }
      echo "sanitize: asan build of the fuzz corpus replay ($build)"
      cmake --build "$build" -j "$jobs" --target fragg_fuzz_corpus_test \
        >"$build/sanitize-build.log" 2>&1 ||
        { grep -E "error" "$build/sanitize-build.log" | head -20; status=1; continue; }
      export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1"
      export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
      # Missing is a failure here (run_test would skip a binary that was not built).
      [ -x "$build/test/fragg_fuzz_corpus_test" ] ||
        { echo "  fragg_fuzz_corpus_test: not built"; status=1; continue; }
      run_test "$build/fuzz_replay.sanitize.log" "$build/test/fragg_fuzz_corpus_test" || status=1
      ;;
    tsan)
      build="${FRAGG_TSAN_BUILD:-$root/build-tsan}"
      configure "$build" thread || { status=1; continue; }
      echo "sanitize: tsan build ($build)"
      # libgomp is not instrumented: one OpenMP thread, so that TSan sees only the threads the
      # tests start themselves (the map lock tests insert with threads = 1 anyway).
      export OMP_NUM_THREADS=1
      export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1"
      # The server's parts first (no map needed), then the map lock tests (the whole core).
      if cmake --build "$build" -j "$jobs" --target ros_server_parts_test >"$build/sanitize-build.log" 2>&1; then
        run_test "$build/server_parts.sanitize.log" "$build/test/ros_server_parts_test" || status=1
      else
        grep -E "error" "$build/sanitize-build.log" | head -20; status=1
      fi
      if cmake --build "$build" -j "$jobs" --target fragg_core_test >"$build/sanitize-build.log" 2>&1; then
        run_test "$build/map_lock.sanitize.log" "$build/test/fragg_core_test" \
          --gtest_filter='MapLock.*' || status=1
      else
        grep -E "error" "$build/sanitize-build.log" | head -20; status=1
      fi
      ;;
    *) echo "sanitize: unknown step $step (asan | replay | tsan)" >&2; exit 2 ;;
  esac
done
[ "$status" -eq 0 ] && echo "sanitize: clean" || echo "sanitize: findings above"
exit "$status"
