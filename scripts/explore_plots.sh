#!/usr/bin/env bash
# Closed-loop exploration plots (issue 14 item 6): runs fragg_map_explore on the pipe room
# (depth camera) and the campus (LiDAR), both strategies, and plots the explored volume against
# the steps and against the path length, one PNG per scene. Needs gnuplot (gnuplot-nox).
# Usage: bash scripts/explore_plots.sh EXPLORE_BINARY [OUT_DIR (default docs)] [STEPS (default 40)]
#            [SCENE... (default: pipes campus)]
#   writes OUT_DIR/explore_SCENE.png, .csv (per step) and .json (summary). With
#   EXPLORE_PLOT_ONLY=1 an existing OUT_DIR/explore_SCENE.csv is plotted again without a run.
set -euo pipefail
usage="usage: bash scripts/explore_plots.sh EXPLORE_BINARY [OUT_DIR] [STEPS] [SCENE...]"
[ $# -ge 1 ] || { echo "$usage" >&2; exit 2; }
bin="$1" out="${2:-docs}" steps="${3:-40}"
shift $(($# < 3 ? $# : 3))
scenes="${*:-pipes campus}"
[ -x "$bin" ] || { echo "explore_plots: $bin is not an executable (build fragg_map_explore)" >&2; exit 2; }
command -v gnuplot >/dev/null || { echo "explore_plots: gnuplot is missing (apt install gnuplot-nox)" >&2; exit 1; }
mkdir -p "$out"
data="$(mktemp -d)"
trap 'rm -rf "$data"' EXIT
for scene in $scenes; do
  if [ "${EXPLORE_PLOT_ONLY:-0}" != 1 ] || [ ! -f "$out/explore_$scene.csv" ]; then
    "$bin" --scenario "$scene" --steps "$steps" --verbose --csv "$out/explore_$scene.csv" \
      --json "$out/explore_$scene.json"
  fi
  # One file per strategy: "step path_m explored_percent".
  for strategy in gain nearest; do
    awk -F, -v s="$strategy" 'NR > 1 && $2 == s { print $3, $8, 100 * $12 }' \
      "$out/explore_$scene.csv" > "$data/$strategy.dat"
  done
  case "$scene" in
    pipes) title="pipe room, depth camera 640x480 (W2), 10 cm cells" ;;
    campus) title="campus, 128-beam LiDAR (W1) to 30 m, 20 cm cells" ;;
  esac
  gnuplot <<GP
set terminal pngcairo size 1100,450 font ",11"
set output '$out/explore_$scene.png'
set multiplot layout 1,2 title "Exploration of the $title"
set grid
set key bottom right
set ylabel "explored volume (% of observable cells in the box)"
set yrange [0:100]
set xlabel "steps (scans after the first)"
plot '$data/gain.dat' using 1:3 with linespoints lw 2 pt 7 ps 0.6 title 'gain per metre', \
     '$data/nearest.dat' using 1:3 with linespoints lw 2 pt 5 ps 0.6 title 'nearest frontier'
set xlabel "path length (m)"
plot '$data/gain.dat' using 2:3 with linespoints lw 2 pt 7 ps 0.6 title 'gain per metre', \
     '$data/nearest.dat' using 2:3 with linespoints lw 2 pt 5 ps 0.6 title 'nearest frontier'
unset multiplot
GP
  echo "explore_plots: $out/explore_$scene.png"
done
