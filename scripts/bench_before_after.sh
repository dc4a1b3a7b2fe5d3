#!/usr/bin/env bash
# Speed of a change, before against after, in one run on one machine: builds fragg_map_bench
# from an older source tree (BEFORE_DIR, e.g. `git archive <rev> | tar -x -C .device/before`)
# and from this checkout (plain CMake, no ROS), then runs the two benches alternately ROUNDS
# times with the same arguments, so that drift of the machine hits both alike.
# Usage: bash scripts/bench_before_after.sh BEFORE_DIR ROUNDS [fragg_map_bench ARGS...]
# Logs and JSON go to $OUT when set (the device tool brings them back), else out/before_after.
# Env: CUDA_ARCH (default 90; "off" builds without CUDA), JOBS (default: every core),
# AFTER_BUILD (a build folder of this checkout that already has bin/fragg_map_bench, e.g.
# build-device after scripts/device_check.sh: not built again).
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
before_src="$(cd "${1:?usage: bench_before_after.sh BEFORE_DIR ROUNDS [ARGS...]}" && pwd)"
rounds="${2:?rounds}"
shift 2
out="${OUT:-$root/out/before_after}"
mkdir -p "$out"
jobs="${JOBS:-$(nproc)}"
cuda_args=(-DCMAKE_CUDA_ARCHITECTURES="${CUDA_ARCH:-90}")
[ "${CUDA_ARCH:-90}" = off ] && cuda_args=(-DFRAGG_WITH_CUDA=OFF)

build() {  # SRC BUILD_DIR NAME
  cmake -S "$1" -B "$2" -DFRAGG_WITH_ROS=OFF -DFRAGG_BUILD_TESTS=OFF -DCMAKE_BUILD_TYPE=Release \
    "${cuda_args[@]}" -DOCTOMAP_ROOT="$root/.device/octomap" >"$out/cmake_$3.log" 2>&1 &&
    cmake --build "$2" -j "$jobs" --target fragg_map_bench >"$out/build_$3.log" 2>&1 ||
    { echo "build of $3 failed (see $out/build_$3.log)"; grep -E "error" "$out/build_$3.log" | head; exit 1; }
}
after_build="${AFTER_BUILD:-$root/build-after}"
build "$before_src" "$root/build-before" before
[ -x "$after_build/bin/fragg_map_bench" ] || build "$root" "$after_build" after
echo "built before ($before_src) and after ($root, in $after_build)"
export LD_LIBRARY_PATH="$root/.device/octomap/lib:${LD_LIBRARY_PATH:-}"
for r in $(seq 1 "$rounds"); do
  for which in before after; do
    bin="$root/build-before/bin/fragg_map_bench"
    [ "$which" = after ] && bin="$after_build/bin/fragg_map_bench"
    "$bin" "$@" --json "$out/${which}_$r.json" \
      >"$out/${which}_$r.log" 2>&1 || { echo "$which round $r failed"; tail -5 "$out/${which}_$r.log"; }
    echo "== $which, round $r"
    grep -E "ms/scan|median|fragg-" "$out/${which}_$r.log" | head -12
  done
done
