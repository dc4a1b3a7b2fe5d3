#!/usr/bin/env bash
# The frontier picture of docs/planning.md (docs/frontiers.png): the simulator's pump room
# (config/scenes/pipes.json) seen by a depth camera (320 x 240, 70 degrees, 8 m, pitched 10
# degrees down) at 24 poses along the first 12 m of its survey trajectory, mapped at 10 cm with
# `fragg_map build`, then `fragg_map render --frontiers`: the frontier cells at the camera's
# height (centres 1.6 to 2.0 m) in clusters of >= 20 cells, a colour each, and the best
# viewpoint of each cluster (pinhole gain sensor, 8 m) as a white disc with its heading, over
# the faded top view.
# Usage: bash scripts/make_frontiers_png.sh [--bin DIR] [--out PNG]
#   --bin DIR    folder with fragg_map and fragg_map_sim (default: ws/devel/lib/fragg_map, else
#                build-core/bin)
#   --out PNG    default docs/frontiers.png
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
bin="" png="$repo/docs/frontiers.png"
while [ $# -gt 0 ]; do
  case "$1" in
    --bin) bin="${2:?}"; shift 2 ;;
    --out) png="${2:?}"; shift 2 ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    *) echo "make_frontiers_png: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
if [ -z "$bin" ]; then
  if [ -x "$repo/ws/devel/lib/fragg_map/fragg_map" ]; then bin="$repo/ws/devel/lib/fragg_map"
  else bin="$repo/build-core/bin"; fi
fi
fm="$bin/fragg_map" sim="$bin/fragg_map_sim"
for exe in "$fm" "$sim"; do
  [ -x "$exe" ] || { echo "make_frontiers_png: no $(basename "$exe") in $bin (build first)" >&2; exit 1; }
done
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

set -x
"$sim" record "$repo/config/scenes/pipes.json" --trajectory survey --sensor depth --seed 202 \
  --frames 24 --rate 2 --width 320 --height 240 --hfov 70 --depth-max-range 8 --mount-pitch 10 \
  --depth-folder "$tmp/depth"
"$fm" build "$tmp/depth" -o "$tmp/map.fgm" --resolution 0.1
frontier_options=(--height 1.6 2.0 --min-cluster 20 --viewpoints 1 --max-range 8)
"$fm" frontiers "$tmp/map.fgm" "${frontier_options[@]}"
"$fm" render "$tmp/map.fgm" -o "$png" --scale 4 --frontiers "${frontier_options[@]}"
set +x
echo "make_frontiers_png: $(du -h "$png" | cut -f1) $png"
