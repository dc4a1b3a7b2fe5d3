#!/usr/bin/env bash
# On the GPU machine: runs what scripts/stage_prebuilt.sh staged (carry .device/pre, or the
# --dest given there as FRAGG_PREBUILT, with .device/octomap and .device/store), no build. Steps, in the order given (default: insert gains
# tests):
#   insert  W1 30 m insertion, batch and one insert (fragg_map_bench --backends cuda+sequence
#           cuda), this tree and the staged base alternated, twice; the stage lines too
#   gains   the gain of 1,000 viewpoints with each kernel in GAIN_KERNELS (default
#           "pooled-deferred sized pooled plain"), each in its own process, twice
#   tests   the staged gpu test programs (fragg_gpu_*), each with a 120 s limit
#   memcheck  compute-sanitizer memcheck on a short gain run of each GAIN_KERNELS kernel
# W1 is generated first (scripts/make_workloads.sh with the staged simulator). Logs go
# to $OUT (the device tool brings them back).
# Usage: bash scripts/device_prebuilt.sh [insert] [gains] [tests] [memcheck]
set -uo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
out=${OUT:-/tmp/fragg_prebuilt_out}
mkdir -p "$out"
pre=${FRAGG_PREBUILT:-$top/.device/pre}  # stage_prebuilt.sh's --dest
export LD_LIBRARY_PATH="$pre/lib:$top/.device/octomap/lib:$top/.device/store/lib:${LD_LIBRARY_PATH:-}"
# The tests' scratch folder (their built-in one is this machine's build tree).
export FRAGG_TEST_TMP=${FRAGG_TEST_TMP:-/tmp/fragg_test_tmp}
mkdir -p "$FRAGG_TEST_TMP"
steps=("$@")
[ ${#steps[@]} -eq 0 ] && steps=(insert gains tests)
nvidia-smi -L || echo "no nvidia-smi"
echo "head $(tr '\n' ' ' <"$pre/head/COMMIT"); base $(cat "$pre/base/COMMIT" 2>/dev/null || echo none)"
t0=$SECONDS
missing=$(ldd "$pre"/head/* 2>/dev/null | grep "not found" | sort -u)
[ -n "$missing" ] && { echo "missing libraries: $missing"; exit 1; }
wl=/tmp/fragg_wl
[ -d "$wl/w1_lidar360" ] ||
  bash "$top/scripts/make_workloads.sh" --out "$wl" --only w1 --sim "$pre/head/fragg_map_sim" 2>&1 | tail -1
echo "== W1 ready: $((SECONDS - t0)) s"
kernels=${GAIN_KERNELS:-pooled-deferred sized pooled plain}
status=0
for step in "${steps[@]}"; do
  case "$step" in
    insert)
      for rep in 1 2; do
        for c in head base; do
          [ -x "$pre/$c/fragg_map_bench" ] || continue
          log="$out/insert_${c}_$rep.log"
          "$pre/$c/fragg_map_bench" --no-real --synthetic-scans 0 --workloads "$wl" \
            --only "W1 lidar360 30 m" --backends cuda+sequence cuda --octomap-scans 0 \
            --repeats 2 >"$log" 2>&1 || status=1
          echo "== insert $c ($rep): $(grep -E '^\| W1 lidar360 30' "$log" | awk -F'|' '{print $7, $9, $10}' | tr '\n' ';') ($((SECONDS - t0)) s)"
          grep -E "stages ms/scan\] W1 lidar360 30" "$log" | head -2
        done
      done ;;
    gains)
      for rep in 1 2; do
        for k in $kernels; do
          log="$out/gains_${k}_$rep.log"
          timeout 60 "$pre/head/fragg_map_frontier_bench" --workloads "$wl" --backend cuda \
            --gain-kernel "$k" >"$log" 2>&1 || status=1
          echo "== gain $k ($rep): $(grep -E '^gain of' "$log" | head -1) ($((SECONDS - t0)) s)"
        done
      done ;;
    tests)
      for t in "$pre"/head/fragg_gpu_*; do
        name=$(basename "$t")
        timeout 120 "$t" >"$out/$name.log" 2>&1 || status=1
        echo "== $name: $(grep -cE '^\[ +OK' "$out/$name.log") ok, $(grep -cE '^\[ +SKIPPED' "$out/$name.log") skipped, $(grep -cE '^\[ +FAILED +\]' "$out/$name.log") failed ($((SECONDS - t0)) s)"
        grep -E "^\[ +FAILED|Failure|threw" "$out/$name.log" | head -6
      done ;;
    memcheck)
      for k in $kernels; do
        timeout 90 compute-sanitizer --tool memcheck "$pre/head/fragg_map_frontier_bench" \
          --workloads "$wl" --backend cuda --max-scans 2 --viewpoints 20 --gain-kernel "$k" \
          >"$out/memcheck_$k.log" 2>&1 || status=1
        echo "== memcheck $k: $(grep -E 'ERROR SUMMARY' "$out/memcheck_$k.log")"
      done ;;
    *) echo "unknown step $step"; status=1 ;;
  esac
done
echo "== done: $((SECONDS - t0)) s"
exit $status
