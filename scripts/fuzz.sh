#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, -DFRAGG_FUZZ=ON) and runs them, each for SECONDS
# (default 60), starting from the committed corpus test/fuzz/corpus/<target> plus the findings
# of earlier runs (FRAGG_FUZZ_WORK/<target>/corpus; the committed corpus is not written to).
# Crashes land in FRAGG_FUZZ_WORK/<target>/ as crash-*, leak-*, oom-* or timeout-*.
# Usage: bash scripts/fuzz.sh [TARGET|all] [SECONDS]
#   TARGET: fgm scan pcd ply xyz kitti_bin scan_graph poses waypoints obj cloud_msg
# Environment: FRAGG_FUZZ_BUILD (build folder, default build-fuzz), FRAGG_FUZZ_WORK (default
# <build>/fuzz-work), FRAGG_FUZZ_JOBS (build jobs, default 2), FRAGG_FUZZ_ARGS (extra libFuzzer
# flags, e.g. -jobs=2). Needs clang and libFuzzer: bash scripts/install_deps.sh clang-14
# libfuzzer-14-dev libomp-14-dev.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
target="${1:-all}"
seconds="${2:-60}"
build="${FRAGG_FUZZ_BUILD:-$root/build-fuzz}"
work="${FRAGG_FUZZ_WORK:-$build/fuzz-work}"
cxx="$(command -v clang++-14 || command -v clang++ || true)"
[ -n "$cxx" ] || { echo "fuzz.sh: clang++ not found (install clang-14 libfuzzer-14-dev)" >&2; exit 1; }

cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER="$cxx" -DFRAGG_FUZZ=ON -DFRAGG_WITH_ROS=OFF \
  -DFRAGG_WITH_CUDA=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -DNDEBUG" \
  >"$build.cmake.log" 2>&1 || { tail -20 "$build.cmake.log"; exit 1; }
# The targets this configuration builds (cloud_msg only where the ROS headers are found).
mapfile -t all < <(cmake --build "$build" --target help | sed -n 's/^\.\.\. fragg_fuzz_\([a-z_]*\)$/\1/p' |
  grep -vx "io_lib\|corpus_test")
if [ "$target" = all ]; then targets=(${all[@]}); else targets=("$target"); fi
cmake --build "$build" -j "${FRAGG_FUZZ_JOBS:-2}" --target "${targets[@]/#/fragg_fuzz_}"

status=0
for t in "${targets[@]}"; do
  mkdir -p "$work/$t/corpus"
  echo "fuzz.sh: $t for ${seconds} s (log $work/$t/fuzz.log)"
  # -rss_limit_mb: a reader must not need more than 2 GiB for a small input; -timeout: 60 s of
  # wall time (a loaded machine starves a nice-19 fuzzer for seconds; a real hang still shows).
  (cd "$work/$t" && "$build/fuzz/fragg_fuzz_$t" corpus "$root/test/fuzz/corpus/$t" \
    -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=60 -print_final_stats=1 \
    ${FRAGG_FUZZ_ARGS:-} >fuzz.log 2>&1) || status=1
  grep -E "^#[0-9]+ *DONE|^stat::number_of_executed_units|^stat::average_exec_per_sec|ERROR|SUMMARY" \
    "$work/$t/fuzz.log" | head -8
done
[ "$status" -eq 0 ] && echo "fuzz.sh: no finding" || echo "fuzz.sh: findings above (inputs in $work/<target>/)"
exit "$status"
