#!/usr/bin/env bash
# The paper's Fig. 5b from a fragg_map_bench JSON file: insertion time per frame against the
# resolution (W2 depth: 2, 5, 10, 20 cm), one line per engine. Needs gnuplot (gnuplot-nox).
# Usage: bash scripts/plot_fig5b.sh BENCH.json OUT.png
set -euo pipefail
[ $# -eq 2 ] || { echo "usage: bash scripts/plot_fig5b.sh BENCH.json OUT.png" >&2; exit 2; }
json="$1" png="$2"
command -v gnuplot >/dev/null || { echo "plot_fig5b: gnuplot is missing (apt install gnuplot-nox)" >&2; exit 1; }
data="$(mktemp)"
trap 'rm -f "$data"' EXIT
# One block per engine: "resolution_cm ms_median", blocks separated by two blank lines.
/usr/bin/python3 - "$json" > "$data" <<'PY'
import json, sys
rows = {}
for w in json.load(open(sys.argv[1])):
    if w.get("group") != "W2":
        continue
    for r in w["results"]:
        rows.setdefault(r["engine"], []).append((w["resolution_m"] * 100, r["ms_median"], r["scans_timed"]))
if not rows:
    sys.exit("plot_fig5b: no W2 rows in the JSON (run fragg_map_bench --workloads DIR)")
for engine, pts in rows.items():
    n = sorted(set(p[2] for p in pts))
    frames = "/".join(str(x) for x in n)
    print(f"# {engine}_({frames}_frames)")
    for res, ms, n in sorted(pts):
        print(f"{res:g} {ms:.3f} {n}")
    print("\n")
PY
engines="$(grep '^# ' "$data" | sed 's/^# //')"
plot=""
i=0
for e in $engines; do
  plot="$plot${plot:+, }'$data' index $i using 1:2 with linespoints lw 2 pt 7 title '${e//_/ }'"
  i=$((i + 1))
done
gnuplot <<GP
set terminal png size 900,600 font ",12"
set output '$png'
set title "W2 depth (640x480, pipes scene): insertion time per frame against resolution"
set xlabel "resolution (cm)"
set ylabel "ms per frame (median)"
set logscale y
set xtics (2, 5, 10, 20)
set grid
set key top right
plot $plot
GP
echo "plot_fig5b: $png"
