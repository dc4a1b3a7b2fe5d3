#!/usr/bin/env bash
# The paper's Fig. 5a from a fragg_map_loop_bench JSON file: time to correct the poses of k
# scans (remove + re-insert) against k, one line per engine, with each engine's full rebuild
# as a flat line. Needs gnuplot (gnuplot-nox).
# Usage: bash scripts/plot_fig5a.sh LOOP.json OUT.png [TITLE]
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: bash scripts/plot_fig5a.sh LOOP.json OUT.png [TITLE]" >&2; exit 2; }
json="$1" png="$2" title="${3:-}"
command -v gnuplot >/dev/null || { echo "plot_fig5a: gnuplot is missing (apt install gnuplot-nox)" >&2; exit 1; }
data="$(mktemp)"
trap 'rm -f "$data"' EXIT
# Per engine two blocks: "k ms_total" of the corrections, then "k rebuild_ms" at both ends.
/usr/bin/python3 - "$json" > "$data" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
if not j.get("engines"):
    sys.exit("plot_fig5a: no engines in the JSON (run fragg_map_loop_bench --json FILE)")
for e in j["engines"]:
    rows = sorted((r["k"], r["ms_total"]) for r in e["rows"])
    print(f"# {e['engine']}_correct")
    for k, ms in rows:
        print(f"{k} {ms:.3f}")
    print("\n")
    print(f"# {e['engine']}_rebuild_({e['scans']}_scans)")
    for k in (rows[0][0], rows[-1][0]):
        print(f"{k} {e['rebuild_ms']:.3f}")
    print("\n")
PY
names="$(grep '^# ' "$data" | sed 's/^# //')"
plot=""
i=0
for n in $names; do
  style="linespoints lw 2 pt 7"
  case "$n" in *rebuild*) style="lines lw 2 dt 2" ;; esac
  plot="$plot${plot:+, }'$data' index $i using 1:2 with $style title '${n//_/ }'"
  i=$((i + 1))
done
[ -n "$title" ] || title="$(/usr/bin/python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(f\"pose correction of the last k scans ({j['points_per_scan']} points per scan, {j['resolution_m']*100:g} cm, {j['max_range_m']:g} m)\")" "$json")"
gnuplot <<GP
set terminal png size 900,600 font ",12"
set output '$png'
set title "$title"
set xlabel "scans corrected (k)"
set ylabel "ms (total)"
set logscale xy
set autoscale xfix
set offsets graph 0.03, graph 0.08, 0, 0
set grid
set key top left
plot $plot
GP
echo "plot_fig5a: $png"
