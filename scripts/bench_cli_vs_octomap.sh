#!/usr/bin/env bash
# The whole `fragg_map build` process against OctoMap's insertion of the same scans, in one run:
# fragg is timed from process start to exit (reading the scans, inserting, writing the .fgm,
# the final stats); OctoMap by `fragg_map octomap-build`'s own timer around insertPointCloud
# (its reading and its .bt writing not counted). Runs alternate (fragg, OctoMap, fragg, ...)
# so that drift of a shared machine hits both; with --before BIN, a second fragg_map (e.g. an
# older build) is timed in the same rounds, before and after alternating.
# Usage: bash scripts/bench_cli_vs_octomap.sh --input DIR [--scans 10] [--resolution 0.1]
#          [--max-range 80] [--rounds 3] [--octomap-rounds 1] [--bin DIR] [--before BIN]
#          [--out DIR] [--backend cpu]
# Prints one line per run and a summary: medians and the ratio OctoMap insertion / fragg process.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
input="" scans=10 resolution=0.1 range=80 rounds=3 octo_rounds=1 bin="" before="" out=""
backend=cpu
while [ $# -gt 0 ]; do
  case "$1" in
    --input) input="$2"; shift 2 ;;
    --scans) scans="$2"; shift 2 ;;
    --resolution) resolution="$2"; shift 2 ;;
    --max-range) range="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    --octomap-rounds) octo_rounds="$2"; shift 2 ;;
    --bin) bin="$2"; shift 2 ;;
    --before) before="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --backend) backend="$2"; shift 2 ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "bench_cli_vs_octomap: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[ -n "$input" ] || { echo "bench_cli_vs_octomap: give --input (a KITTI folder, bag, ...)" >&2; exit 2; }
fm="${bin:-$repo/build-core/bin}/fragg_map"
[ -x "$fm" ] || { echo "bench_cli_vs_octomap: no fragg_map at $fm (build first, or --bin)" >&2; exit 1; }
[ -z "$before" ] || [ -x "$before" ] || { echo "bench_cli_vs_octomap: no $before" >&2; exit 1; }
out="${out:-$(mktemp -d)}"
mkdir -p "$out"
args=("$input" --scans "$scans" --resolution "$resolution" --max-range "$range")

# fragg NAME BIN ROUND: the whole process, wall clock (and its CPU seconds, user + system,
# which a loaded machine disturbs less); the JSON keeps the stage figures.
fragg_run() {
  /usr/bin/time -o "$out/$1_$3.time" -f "%e %U %S" \
    "$2" build "${args[@]}" --backend "$backend" -o "$out/$1_$3.fgm" --json >"$out/$1_$3.json"
  cut -d' ' -f1 "$out/$1_$3.time" >"$out/$1_$3.s"
  python3 - "$out/$1_$3.json" "$out/$1_$3.time" "$1" "$3" "$out/$1_$3.fgm" <<'EOF'
import json, os, sys
j = json.load(open(sys.argv[1]))
wall, user, sys_s = (float(v) for v in open(sys.argv[2]).read().split())
print("%s round %s: process %.3f s (CPU %.3f s), insertion loop %.3f s (insert %.3f s), "
      "%d scans, %d points, %d known voxels, map %.1f MiB" % (sys.argv[3], sys.argv[4], wall,
      user + sys_s, j["seconds"], j["insert_seconds"], j["scans"], j["points"],
      j["known_voxels"], os.path.getsize(sys.argv[5]) / 1048576.0))
EOF
}
octo_run() {
  /usr/bin/time -o "$out/octomap_$1.time" -f "%e %U %S" \
    "$fm" octomap-build "${args[@]}" -o "$out/octomap_$1.bt" >"$out/octomap_$1.log"
  sed -n 's/.* \([0-9.]*\) s in insertPointCloud.*/\1/p' "$out/octomap_$1.log" >"$out/octomap_$1.s"
  echo "octomap round $1: insertion $(cat "$out/octomap_$1.s") s; whole octomap-build process" \
    "(wall user system) $(cat "$out/octomap_$1.time") ($(cat "$out/octomap_$1.log"))"
}

echo "bench_cli_vs_octomap: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg), $(date -u +%FT%TZ)"
for r in $(seq 1 "$rounds"); do
  fragg_run after "$fm" "$r"
  [ -z "$before" ] || fragg_run before "$before" "$r"
  [ "$r" -gt "$octo_rounds" ] || octo_run "$r"
done
echo "bench_cli_vs_octomap: load at the end $(cut -d' ' -f1-3 /proc/loadavg)"
python3 - "$out" "$rounds" "$octo_rounds" "$before" <<'EOF'
import statistics, sys
out, rounds, octo_rounds, before = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
read = lambda name, n: [float(open("%s/%s_%d.s" % (out, name, r)).read()) for r in range(1, n + 1)]
octo_runs = read("octomap", min(rounds, octo_rounds))
octo = statistics.median(octo_runs) if octo_runs else float("nan")
for name in ["after"] + (["before"] if before else []):
    s = read(name, rounds)
    m = statistics.median(s)
    print("%s: fragg_map build process median %.3f s (runs %s); OctoMap insertion %.2f s; "
          "ratio %.1fx" % (name, m, ", ".join("%.3f" % v for v in s), octo, octo / m))
EOF
