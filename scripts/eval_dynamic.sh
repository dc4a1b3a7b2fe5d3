#!/usr/bin/env bash
# Moving objects side by side (issue 37), after scripts/make_workloads.sh (w5, w6): builds
# fragg's map with the dynamic option off and on (CPU backend, one thread) and OctoMap's map of
# the same scans (ground-truth poses), then runs
#   fragg_map eval MAP --scene STATIC_TRUTH.obj --labels DATASET --label-max-range R --json
# on each and prints a markdown table: SA (static points kept), DA (dynamic points removed),
# ghost cells (occupied, free in the static truth), ms per scan (median, whole insert).
#   W5 w5_movers: 10 cm, max range 30 m, fragg given the LiDAR's range noise (--range-noise 0.01)
#   W6 w6_people: 5 cm, max range 6 m, fragg given the camera's (--range-noise-quadratic 0.001)
# (the noise is fragg's clearing margin: cells just in front of a hit are not cleared, so
# they do not become void under noisy static hits; OctoMap has no such model)
# Usage: bash scripts/eval_dynamic.sh [--workloads DIR] [--out DIR] [--bin DIR] [--only w5|w6]
#                                     [--rule pass-through|surround] [--known-radius N] [--reuse]
#   --rule    the "on" map's void rule (fragg_map build --dynamic-rule; default pass-through)
#   --known-radius  the "on" map's neighbourhood radius in cells (fragg_map build --known-radius;
#             default: the map's, 2)
#   --reuse   keeps OctoMap's .bt when present
#   --no-return  W5: both fragg maps also clear the LiDAR's no-return beams (--clear-no-return
#             with W5's beam table: --sensor lidar, 32 rings over -25..15 degrees, 1024
#             columns; the KITTI .bin keeps no NaN). W6's depth images carry no beam table.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
workloads="${FRAGG_WORKLOADS:-$HOME/.cache/fragg_map/workloads}"
out="" bin="" only="w5,w6" reuse=0 rule=pass-through radius="" no_return=0
while [ $# -gt 0 ]; do
  case "$1" in
    --workloads) workloads="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --bin) bin="$2"; shift 2 ;;
    --only) only="$2"; shift 2 ;;
    --reuse) reuse=1; shift ;;
    --no-return) no_return=1; shift ;;
    --rule) rule="$2"; shift 2 ;;
    --known-radius) radius="$2"; shift 2 ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) echo "eval_dynamic: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
out="${out:-$workloads/eval_dynamic}"
if [ -z "$bin" ]; then
  if [ -x "${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map/fragg_map" ]; then bin="${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map"
  else bin="$repo/build-core/bin"; fi
fi
fm="$bin/fragg_map"
[ -x "$fm" ] || { echo "eval_dynamic: no fragg_map in $bin (build first)" >&2; exit 1; }
mkdir -p "$out"

run() {  # name dataset static_obj resolution range [fragg build args: the sensor's noise]
  local name="$1" data="$2" obj="$3" res="$4" range="$5"
  shift 5
  [ -d "$data/labels" ] || { echo "eval_dynamic: $data has no labels/ (make_workloads.sh --only $name)" >&2; exit 1; }
  for mode in off on; do
    local flag=()
    [ "$mode" = on ] && flag=(--dynamic --dynamic-rule "$rule")
    [ "$mode" = on ] && [ -n "$radius" ] && flag+=(--known-radius "$radius")
    "$fm" build "$data" -o "$out/${name}_$mode.fgm" --resolution "$res" --max-range "$range" \
      --backend cpu --threads 1 "$@" "${flag[@]}" --json > "$out/${name}_$mode.build.json"
  done
  if [ "$reuse" = 0 ] || [ ! -f "$out/${name}_octomap.bt" ]; then
    "$fm" octomap-build "$data" -o "$out/${name}_octomap.bt" --resolution "$res" \
      --max-range "$range" > "$out/${name}_octomap.log"
  fi
  "$fm" eval "$out/${name}_off.fgm" --scene "$obj" --labels "$data" --label-max-range "$range" \
    --octomap "$out/${name}_octomap.bt" --json > "$out/${name}_off.eval.json"
  "$fm" eval "$out/${name}_on.fgm" --scene "$obj" --labels "$data" --label-max-range "$range" \
    --json > "$out/${name}_on.eval.json"
  python3 - "$out" "$name" <<'PY'
import json, re, sys
out, name = sys.argv[1], sys.argv[2]
off = json.load(open(f"{out}/{name}_off.eval.json"))
on = json.load(open(f"{out}/{name}_on.eval.json"))
octo_ms = re.search(r"\(([0-9.]+) ms/scan\)", open(f"{out}/{name}_octomap.log").read())
rows = [("fragg, option off", off["map"], json.load(open(f"{out}/{name}_off.build.json"))["ms_per_scan"]["median"]),
        ("fragg, option on", on["map"], json.load(open(f"{out}/{name}_on.build.json"))["ms_per_scan"]["median"]),
        ("OctoMap", off["octomap"], float(octo_ms.group(1)) if octo_ms else float("nan"))]
print(f"| {name} | SA % | DA % | ghost cells | occupied | ms/scan |")
print("|---|---|---|---|---|---|")
for label, m, ms in rows:
    d = m["dynamic"]
    print(f"| {label} | {100*d['sa']:.2f} | {100*d['da']:.2f} | {d['ghost_cells']:,} | {d['occupied']:,} | {ms:.1f} |")
PY
}

for w in ${only//,/ }; do
  case "$w" in
    w5)
      w5_beams=()
      [ "$no_return" = 1 ] && w5_beams=(--clear-no-return --sensor lidar --elevation-min -25
        --elevation-max 15 --lidar-height 32 --lidar-width 1024)
      run w5 "$workloads/w5_movers" "$workloads/scenes/campus_movers.obj" 0.1 30 \
        --range-noise 0.01 "${w5_beams[@]}" ;;
    w6) run w6 "$workloads/w6_people" "$workloads/scenes/office_people.obj" 0.05 6 \
      --range-noise-quadratic 0.001 ;;
    *) echo "eval_dynamic: unknown workload '$w'" >&2; exit 2 ;;
  esac
done
