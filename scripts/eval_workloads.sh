#!/usr/bin/env bash
# Map quality against ground truth on the standard workloads (after scripts/make_workloads.sh):
# builds fragg's and OctoMap's maps of the same scans (ground-truth poses) and runs
# `fragg_map eval MAP --scene OBJ --octomap BT --json` on them, then prints a markdown table.
#   W1 lidar360, 5 cm, max range 30 m and 50 m, all 100 scans (OctoMap: ~35 s per 180k-point
#     scan, one core: about an hour for each range), or the first --octomap-scans N (then
#     fragg alone also on all 100)
#   W2 depth, 5 cm, all 100 frames
#   each again with the simulated sensor's range noise given to fragg (--range-noise 0.02 for
#   W1's LiDAR, --range-noise-quadratic 0.001 for W2's depth camera), against the same .bt
# Usage: bash scripts/eval_workloads.sh [--workloads DIR] [--out DIR] [--octomap-scans N]
#                                       [--bin DIR] [--reuse]
# --reuse keeps maps already built in the output folder (default: out = WORKLOADS/eval).
# The last column says where fragg's map is worse than OctoMap's, if anywhere.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
workloads="${FRAGG_WORKLOADS:-$HOME/.cache/fragg_map/workloads}"
out=""
octomap_scans=0
bin=""
reuse=0
while [ $# -gt 0 ]; do
  case "$1" in
    --workloads) workloads="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --octomap-scans) octomap_scans="$2"; shift 2 ;;
    --bin) bin="$2"; shift 2 ;;
    --reuse) reuse=1; shift ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "eval_workloads: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
out="${out:-$workloads/eval}"
if [ -z "$bin" ]; then
  if [ -x "${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map/fragg_map" ]; then bin="${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map"
  else bin="$repo/build-core/bin"; fi
fi
fm="$bin/fragg_map"
[ -x "$fm" ] || { echo "eval_workloads: no fragg_map in $bin (build first)" >&2; exit 1; }
mkdir -p "$out"

# name input scene max_range scans(0 = all) octomap(- = none, else the .bt's name) [build args]
# The OctoMap map is built once per name (a run with fragg options reuses its base run's).
evaluate() {
  local name="$1" input="$2" scene="$3" range="$4" scans="$5" octo="$6"
  shift 6
  echo "eval_workloads: $name" >&2
  if [ "$reuse" = 0 ] || [ ! -f "$out/$name.fgm" ]; then
    "$fm" build "$input" -o "$out/$name.fgm" --resolution 0.05 --max-range "$range" \
      --scans "$scans" "$@" --json > "$out/$name.build.json"
  fi
  local octo_args=()
  if [ "$octo" != - ]; then
    if [ ! -f "$out/$octo.bt" ] || { [ "$reuse" = 0 ] && [ "$octo" = "$name" ]; }; then
      "$fm" octomap-build "$input" -o "$out/$octo.bt" --resolution 0.05 --max-range "$range" \
        --scans "$scans" >&2
    fi
    octo_args=(--octomap "$out/$octo.bt")
  fi
  "$fm" eval "$out/$name.fgm" --scene "$scene" "${octo_args[@]}" --json > "$out/$name.eval.json"
  # The same with OctoMap's occupancy rule on both maps (fragg's default unknown band aside).
  "$fm" eval "$out/$name.fgm" --scene "$scene" "${octo_args[@]}" --octomap-threshold --json \
    > "$out/$name.eval_octorule.json"
}

w1="$workloads/w1_lidar360" w2="$workloads/w2_depth"
campus="$workloads/scenes/campus.obj" pipes="$workloads/scenes/pipes.obj"
first=all
case "$octomap_scans" in 0 | 100) octomap_scans=0 ;; *) first="first${octomap_scans}" ;; esac
for range in 30 50; do
  evaluate "w1_${range}m_$first" "$w1" "$campus" "$range" "$octomap_scans" "w1_${range}m_$first"
  evaluate "w1_${range}m_${first}_noise" "$w1" "$campus" "$range" "$octomap_scans" \
    "w1_${range}m_$first" --range-noise 0.02
done
if [ "$first" != all ]; then
  evaluate w1_30m_all "$w1" "$campus" 30 0 -
  evaluate w1_30m_all_noise "$w1" "$campus" 30 0 - --range-noise 0.02
fi
evaluate w2_5cm_all "$w2" "$pipes" -1 0 w2_5cm_all
evaluate w2_5cm_all_noise "$w2" "$pipes" -1 0 w2_5cm_all --range-noise-quadratic 0.001

/usr/bin/python3 - "$out" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
print("| run | rule | engine | occupied | precision | surface (observed region) | recall | recall (known surface) | free | free error | deep free error | fragg vs OctoMap |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")

def verdict(j):
    """Where fragg's map is worse than OctoMap's (higher is better for the first three)."""
    if "octomap" not in j:
        return ""
    a, b = j["map"], j["octomap"]
    worse = [k for k in ("precision", "recall", "known_surface_recall") if a[k] < b[k]]
    worse += [k for k in ("free_error", "free_error_deep") if a[k] > b[k]]
    return "at least as good on every column" if not worse else "worse on " + ", ".join(worse)

for path in sorted(glob.glob(os.path.join(out, "*.eval*.json"))):
    j = json.load(open(path))
    name = os.path.basename(path).split(".eval")[0]
    rule = "OctoMap's (p >= 0.5)" if j["octomap_threshold"] else "own (band 0.05)"
    for engine in ("map", "octomap"):
        if engine not in j:
            continue
        q = j[engine]
        print(f"| {name} | {rule} | {'fragg' if engine == 'map' else 'OctoMap'} | {q['occupied']:,} | "
              f"{100*q['precision']:.3f} % | {q['surface_observed']:,} | {100*q['recall']:.3f} % | "
              f"{100*q['known_surface_recall']:.3f} % | {q['free']:,} | "
              f"{100*q['free_error']:.4f} % ({q['free_inside']:,}) | "
              f"{100*q['free_error_deep']:.5f} % ({q['free_inside_deep']:,}) | "
              f"{verdict(j) if engine == 'map' else ''} |")
PY
