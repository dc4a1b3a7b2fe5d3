#!/usr/bin/env bash
# The sub-map picture of docs/submaps.md (docs/submaps.png): W1's map at 10 cm, cut with
# `fragg_map truncate --box` and merged back with `fragg_map merge --mode overwrite`, drawn
# side by side from the top: the map left after the cut (--rest), the cut-out part, and the
# merged result (checked equal to the original with `fragg_map compare`). The three panels are
# one map: the part and the result are merged into the rest 120 m and 240 m east of it with
# whole-voxel --transform shifts (exact), then `fragg_map render --view top`.
# Usage: bash scripts/render_submaps.sh [--workloads DIR] [--bin DIR] [--out PNG]
#   --workloads DIR  workload cache with w1_lidar360 (made with scripts/make_workloads.sh
#                    --only w1 when missing; default $FRAGG_WORKLOADS or
#                    ~/.cache/fragg_map/workloads)
#   --bin DIR        folder with fragg_map (default: <checkout>_ws/devel/lib/fragg_map, else build-core/bin)
#   --out PNG        default docs/submaps.png
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
workloads="${FRAGG_WORKLOADS:-$HOME/.cache/fragg_map/workloads}"
bin="" png="$repo/docs/submaps.png"
while [ $# -gt 0 ]; do
  case "$1" in
    --workloads) workloads="${2:?}"; shift 2 ;;
    --bin) bin="${2:?}"; shift 2 ;;
    --out) png="${2:?}"; shift 2 ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "render_submaps: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
if [ -z "$bin" ]; then
  if [ -x "${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map/fragg_map" ]; then bin="${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map"
  else bin="$repo/build-core/bin"; fi
fi
fm="$bin/fragg_map"
[ -x "$fm" ] || { echo "render_submaps: no fragg_map in $bin (build first)" >&2; exit 1; }
w1="$workloads/w1_lidar360"
if [ ! -f "$w1/poses.txt" ]; then
  sim_args=()
  [ -x "$bin/fragg_map_sim" ] && sim_args=(--sim "$bin/fragg_map_sim")
  bash "$repo/scripts/make_workloads.sh" --out "$workloads" --only w1 "${sim_args[@]}"
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

set -x
"$fm" build "$w1" -o "$tmp/map.fgm" --resolution 0.1 --max-range 30
# A 30 x 30 m square of the street and its trees, from below the ground to above the roofs.
"$fm" truncate "$tmp/map.fgm" --box -10 -15 -5 20 15 30 -o "$tmp/part.fgm" --rest "$tmp/rest.fgm"
"$fm" merge "$tmp/rest.fgm" "$tmp/part.fgm" -o "$tmp/merged.fgm" --mode overwrite
"$fm" compare "$tmp/map.fgm" "$tmp/merged.fgm" --json > "$tmp/compare.json"
set +x
python3 - "$tmp/compare.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
same = c["known_in_a"] == c["known_in_b"] == c["known_in_either"] == c["agreeing"]
print(f"render_submaps: merged vs original: {c['agreeing']} of {c['known_in_either']} known "
      f"cells agree" + ("" if same else " - NOT the original"))
sys.exit(0 if same else 1)
PY
set -x
# The picture: rest | part (+120 m in x) | merged (+240 m), one map, one top view.
"$fm" merge "$tmp/rest.fgm" "$tmp/part.fgm" -o "$tmp/panels2.fgm" --mode overwrite \
  --transform 120 0 0 0 0 0 1
"$fm" merge "$tmp/panels2.fgm" "$tmp/merged.fgm" -o "$tmp/panels3.fgm" --mode overwrite \
  --transform 240 0 0 0 0 0 1
"$fm" render "$tmp/panels3.fgm" --view top --max-size 3600 -o "$png"
set +x
bytes=$(stat -c %s "$png")
echo "render_submaps: $png ($((bytes / 1024)) KiB)"
[ "$bytes" -lt $((2 * 1024 * 1024)) ] || { echo "render_submaps: $png is over 2 MB" >&2; exit 1; }
