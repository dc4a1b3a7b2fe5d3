#!/usr/bin/env bash
# Runs every test: installs the missing Debian packages, builds the catkin workspace (beside the
# checkout: <checkout>_ws by default), runs the gtests with `catkin_make run_tests`, gates on catkin_test_results
# (run_tests itself exits 0 when tests fail) and on the required suites (required_suites below:
# each must have a result, none of its cases failed or skipped), replays the fuzz corpora in an
# ASan + UBSan build and checks the clang-format of the sources.
# Exits non-zero when anything fails. CI runs this (.ci/run).
# Real data is read from ../shared/data/real beside the checkout.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

fragg_usage() {
  echo "usage: bash scripts/test.sh [options]"
  fragg_usage_common
}
fragg_parse_common "$@"

# The suites that must have run and passed in full (a result file with test cases, none failed
# or skipped): each is registered only where its data or library is found, so a missing data file
# or library fails CI here instead of vanishing. One "name=glob" a line (glob: the result file's
# name under build/test_results/fragg_map); add a line for a new suite.
required_suites=(
  "OctoMap agreement=gtest-fragg_agreement_test.xml"
  "OctoMap agreement of a bag through the CLI=gtest-fragg_cli_bag_agreement_test.xml"
  "FCL oracle=gtest-fcl_oracle_test.xml"
  "Velodyne bag rostest=rostest-map_server_bag__topic__velodyne_points*.xml"
  "RGB-D bag rostest with OctoMap agreement=rostest-map_server_bag__topic__camera_depth*.xml"
  "RGB-D rostest=rostest-map_server_rgbd*.xml"
  "real-data loop closure=gtest-fragg_loop_closure_test.xml"
  "fuzz corpus replay=gtest-fragg_fuzz_corpus_test.xml"
)
require_args=()
for suite in "${required_suites[@]}"; do require_args+=(--require "$suite"); done

build="not run" tests="not run" format="not run" sanitize="not run"
failed=0

fragg_install_deps

if fragg_octomap_msgs_standin && fragg_build_ws; then
  build="OK"
  fragg_step "tests (catkin_make run_tests)"
  # Results of earlier runs would hide missing ones: start from an empty folder.
  rm -rf "$FRAGG_WS/build/test_results"
  # --force-cmake: a fresh workspace must be reconfigured once after its first build, or
  # Python tests see a cached empty PYTHONPATH (../shared/ROS.md); it costs a few seconds.
  if fragg_catkin_make --force-cmake run_tests; then
    run_tests_rc=0
  else
    run_tests_rc=$?
  fi
  fragg_step "test results"
  # catkin_test_results is the gate (non-zero on any failure or missing result). Its summary
  # and per-file lines add up gtest's <testsuites> and <testsuite> totals, i.e. twice the test
  # cases: they go to build/catkin_test_results.log (only files with errors or failures shown),
  # and the one total printed comes from the <testcase> elements of the result files
  # themselves (test_counts.py).
  if catkin_test_results "$FRAGG_WS/build/test_results" >"$FRAGG_WS/build/catkin_test_results.log"
  then
    results_rc=0
  else
    results_rc=$?
  fi
  grep -v '^Summary:' "$FRAGG_WS/build/catkin_test_results.log" |
    grep -Ev ': [0-9]+ tests, 0 errors, 0 failures' || true
  if counts="$(/usr/bin/python3 "$FRAGG_REPO/scripts/test_counts.py" \
    "$FRAGG_WS/build/test_results" "${require_args[@]}")"; then
    required_rc=0
  else
    required_rc=$?
  fi
  echo "$counts"
  counts_line="$(printf '%s\n' "$counts" | tail -n 1)"
  if [ "$run_tests_rc" -ne 0 ]; then
    tests="FAILED: catkin_make run_tests exited $run_tests_rc (a test did not build?); $counts_line"
    failed=1
  elif [ "$results_rc" -ne 0 ]; then
    tests="FAILED: $counts_line"
    failed=1
  elif ! printf '%s\n' "$counts_line" | grep -Eq '^[1-9][0-9]* test cases'; then
    tests="FAILED: no test results in $FRAGG_WS/build/test_results"
    failed=1
  elif [ "$required_rc" -ne 0 ]; then
    tests="FAILED: a required suite has no full result (REQUIRED SUITE lines above); $counts_line"
    failed=1
  else
    tests="OK: $counts_line"
  fi
else
  build="FAILED (catkin_make)"
  failed=1
fi

# The fuzz corpus replay again in an ASan + UBSan build (plain CMake, no ROS, no CUDA: only that
# test target and what it links, in <ws>/build-asan-replay, kept between runs), so that a memory
# error or undefined behaviour on a committed input fails CI, not only a crash.
fragg_step "fuzz corpus replay under ASan + UBSan (scripts/sanitize.sh replay)"
if FRAGG_ASAN_BUILD="$FRAGG_WS/build-asan-replay" FRAGG_SANITIZE_JOBS="$FRAGG_JOBS" \
  bash "$FRAGG_REPO/scripts/sanitize.sh" replay; then
  sanitize="OK"
else
  sanitize="FAILED (log under $FRAGG_WS/build-asan-replay)"
  failed=1
fi

fragg_step "format (scripts/check_format.sh)"
if bash "$FRAGG_REPO/scripts/check_format.sh"; then
  format="OK"
else
  format="FAILED (files listed above)"
  failed=1
fi

fragg_step "summary ($(fragg_elapsed))"
echo "build : $build"
echo "tests : $tests"
echo "asan  : $sanitize"
echo "format: $format"
if [ "$failed" -ne 0 ]; then
  echo "test.sh: FAILED"
  exit 1
fi
echo "test.sh: all passed"
