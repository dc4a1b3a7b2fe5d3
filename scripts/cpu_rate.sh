#!/usr/bin/env bash
# What a CPU machine sustains: clouds per second through the map server's path (PointCloud2
# conversion + insertion, CPU backend, no marker subscriber) for 30k, 70k and 180k-point
# clouds of the synthetic 360-degree LiDAR (campus-like scene, max range 30 m) at 5 and 10 cm,
# with fragg_map_ros_overhead (built in the catkin workspace). Prints one markdown row per
# case, with the load average before and after and the share of the cores the run got (its
# CPU time over its wall time): other programs on the machine lower the figures.
# Usage: bash scripts/cpu_rate.sh [--scans N] [--nice N] [--no-build] [common options]
#   --scans N     clouds per case (default 20)
#   --nice N      run the benchmark under nice -n N (default 0)
#   --no-build    use the workspace's binary as it is
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

scans=20 niceness=0 build=1
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --scans) scans="$2"; shift 2 ;;
    --nice) niceness="$2"; shift 2 ;;
    --no-build) build=0; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
fragg_usage() {
  sed -n '8,11p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
  fragg_usage_common
}
fragg_parse_common "${args[@]+"${args[@]}"}"
if [ "$build" = 1 ]; then
  fragg_install_deps
  fragg_build_ws >/dev/null
fi
bench="$FRAGG_WS/devel/lib/fragg_map/fragg_map_ros_overhead"
[ -x "$bench" ] || { echo "cpu_rate: no $bench (build the workspace)" >&2; exit 1; }

echo "$(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "| points a cloud | resolution | clouds/s | ms a cloud | CPU time / wall | load before / after |"
echo "|---:|---|---:|---:|---:|---|"
# rows x columns of the synthetic LiDAR: 30,000, 70,000 and 179,968 points.
for shape in "24 1250" "50 1400" "128 1406"; do
  set -- $shape
  for res in 0.05 0.1; do
    load_before="$(cut -d' ' -f1 /proc/loadavg)"
    line="$(nice -n "$niceness" "$bench" --scans "$scans" --resolution "$res" --max-range 30 \
      --no-markers --beams "$1" --columns "$2" | grep '^sustained:')"
    load_after="$(cut -d' ' -f1 /proc/loadavg)"
    rate="$(sed -E 's/^sustained: ([0-9.]+) clouds.*/\1/' <<<"$line")"
    ms="$(sed -E 's/.*mean ([0-9.]+) ms.*/\1/' <<<"$line")"
    cpu="$(sed -E 's/.*CPU time ([0-9]+) %.*/\1/' <<<"$line")"
    printf '| %s | %s cm | %s | %s | %s %% | %s / %s |\n' "$(($1 * $2))" \
      "$(awk -v r="$res" 'BEGIN { printf "%g", r * 100 }')" "$rate" "$ms" "$cpu" \
      "$load_before" "$load_after"
  done
done
