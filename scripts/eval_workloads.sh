#!/usr/bin/env bash
# Map quality against ground truth on the standard workloads (after scripts/make_workloads.sh):
# builds fragg's and OctoMap's maps of the same scans (ground-truth poses) and runs
# `fragg_map eval MAP --scene OBJ --octomap BT --json` on them, then prints a markdown table.
#   W1 lidar360, 5 cm, max range 30 m and 50 m, the first --octomap-scans scans (OctoMap takes
#     ~35 s per 180k-point scan on 2 cores), and fragg alone on all 100 scans
#   W2 depth, 5 cm, all 100 frames
# Usage: bash scripts/eval_workloads.sh [--workloads DIR] [--out DIR] [--octomap-scans N]
#                                       [--bin DIR] [--reuse]
# --reuse keeps maps already built in the output folder (default: out = WORKLOADS/eval).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
workloads="${FRAGG_WORKLOADS:-$HOME/.cache/fragg_map/workloads}"
out=""
octomap_scans=5
bin=""
reuse=0
while [ $# -gt 0 ]; do
  case "$1" in
    --workloads) workloads="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --octomap-scans) octomap_scans="$2"; shift 2 ;;
    --bin) bin="$2"; shift 2 ;;
    --reuse) reuse=1; shift ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) echo "eval_workloads: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
out="${out:-$workloads/eval}"
if [ -z "$bin" ]; then
  if [ -x "$repo/ws/devel/lib/fragg_map/fragg_map" ]; then bin="$repo/ws/devel/lib/fragg_map"
  else bin="$repo/build-core/bin"; fi
fi
fm="$bin/fragg_map"
[ -x "$fm" ] || { echo "eval_workloads: no fragg_map in $bin (build first)" >&2; exit 1; }
mkdir -p "$out"

# name input scene max_range scans(0 = all) with_octomap
evaluate() {
  local name="$1" input="$2" scene="$3" range="$4" scans="$5" octo="$6"
  echo "eval_workloads: $name" >&2
  if [ "$reuse" = 0 ] || [ ! -f "$out/$name.fgm" ]; then
    "$fm" build "$input" -o "$out/$name.fgm" --resolution 0.05 --max-range "$range" \
      --scans "$scans" --json > "$out/$name.build.json"
  fi
  local octo_args=()
  if [ "$octo" = 1 ]; then
    if [ "$reuse" = 0 ] || [ ! -f "$out/$name.bt" ]; then
      "$fm" octomap-build "$input" -o "$out/$name.bt" --resolution 0.05 --max-range "$range" \
        --scans "$scans" >&2
    fi
    octo_args=(--octomap "$out/$name.bt")
  fi
  "$fm" eval "$out/$name.fgm" --scene "$scene" "${octo_args[@]}" --json > "$out/$name.eval.json"
  # The same with OctoMap's occupancy rule on both maps (fragg's default unknown band aside).
  "$fm" eval "$out/$name.fgm" --scene "$scene" "${octo_args[@]}" --octomap-threshold --json \
    > "$out/$name.eval_octorule.json"
}

evaluate w1_30m_first${octomap_scans} "$workloads/w1_lidar360" "$workloads/scenes/campus.obj" 30 "$octomap_scans" 1
evaluate w1_50m_first${octomap_scans} "$workloads/w1_lidar360" "$workloads/scenes/campus.obj" 50 "$octomap_scans" 1
evaluate w1_30m_all "$workloads/w1_lidar360" "$workloads/scenes/campus.obj" 30 0 0
evaluate w2_5cm_all "$workloads/w2_depth" "$workloads/scenes/pipes.obj" -1 0 1

/usr/bin/python3 - "$out" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
print("| run | rule | engine | occupied | precision | surface (observed region) | recall | recall (known surface) | free | free error | deep free error |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
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
              f"{100*q['free_error_deep']:.5f} % ({q['free_inside_deep']:,}) |")
PY
