#!/usr/bin/env bash
# ~get_frontiers through the node as a user calls it (issue 34's goal): the map server (CPU
# backend, config/default.yaml, so the frontier grid is sized from the LiDAR's beam spacing)
# is fed the first --scans clouds of a KITTI folder (W1 by default), then
# scripts/frontier_service_probe.py asks for the whole map's frontiers with k viewpoints and for
# a box around the last sensor position, while it asks ~get_stats every 50 ms and the next
# --more clouds are played into the node. Prints the probe's JSON (client wall time, the node's
# ms, cells, clusters, the slowest ~get_stats, scans inserted meanwhile). Starts its own master
# on a free loopback port and stops everything it started.
# Usage: bash scripts/frontier_service_bench.sh [--workload DIR] [--scans N] [--more N]
#          [--resolution M] [--max-range M] [--k K] [--box-edge M] [--out DIR] [--no-build]
#          [common options]   (--no-build: the workspace's node as it is)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

workload="${FRAGG_WORKLOADS:-$HOME/.cache/fragg_map/workloads}/w1_lidar360"
scans=10 more=10 resolution=0.05 max_range=80 k=8 box_edge=40 build=1
out="$FRAGG_REPO/out/frontier_service"
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --workload) workload="$2"; shift 2 ;;
    --scans) scans="$2"; shift 2 ;;
    --more) more="$2"; shift 2 ;;
    --resolution) resolution="$2"; shift 2 ;;
    --max-range) max_range="$2"; shift 2 ;;
    --k) k="$2"; shift 2 ;;
    --box-edge) box_edge="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --no-build) build=0; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
fragg_usage() {
  sed -n '10,12p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
  fragg_usage_common
}
fragg_parse_common "${args[@]+"${args[@]}"}"
if [ ! -f "$workload/poses.txt" ]; then
  echo "frontier_service_bench: no KITTI folder at $workload (bash scripts/make_workloads.sh --only w1)" >&2
  exit 1
fi
fragg_install_deps
[ "$build" -eq 0 ] || fragg_build_ws >/dev/null
mkdir -p "$out"
out="$(cd "$out" && pwd -P)"

# Two bags: the first --scans clouds, and the next --more (played during the queries).
all="$out/$(basename "$workload")_$((scans + more)).bag"
first="$out/first_$scans.bag" rest="$out/next_$more.bag"
[ -f "$all" ] || /usr/bin/python3 "$FRAGG_REPO/scripts/kitti_to_bag.py" "$workload" "$all" \
  --scans "$((scans + more))"
split_at="$(/usr/bin/python3 -c 'import sys
t = [float(l) for l in open(sys.argv[1]) if l.strip()]
print(t[int(sys.argv[2])] - t[0])' "$workload/times.txt" "$scans")"
[ -f "$first" ] || rosbag filter "$all" "$first" "t.to_sec() < $(/usr/bin/python3 -c "
import rosbag; b = rosbag.Bag('$all'); print(b.get_start_time() + $split_at - 1e-3)")" >/dev/null
[ -f "$rest" ] || rosbag filter "$all" "$rest" "t.to_sec() >= $(/usr/bin/python3 -c "
import rosbag; b = rosbag.Bag('$all'); print(b.get_start_time() + $split_at - 1e-3)")" >/dev/null
# The box's centre: the last sensor position of the first bag (poses.txt row scans - 1).
center="$(awk -v n="$scans" 'NR == n { print $4, $8, $12 }' "$workload/poses.txt")"

trap fragg_stop_started EXIT
log="$out/frontier_service.log"
: >"$log"
fragg_start_master "$log"
rosparam set /use_sim_time true
rosparam load "$FRAGG_REPO/config/default.yaml" /fragg_map
rosparam set /fragg_map/resolution "$resolution"
rosparam set /fragg_map/backend cpu
rosparam set /fragg_map/sensor_model/max_range "$max_range"
rosparam set /fragg_map/queue_size 100  # every cloud inserted, however slowly
rosparam set /fragg_map/latch false     # no subscriber: no output built
rosrun nodelet nodelet standalone fragg_map/MapServerNodelet __name:=fragg_map \
  cloud_in:=/points >>"$log" 2>&1 &
FRAGG_STARTED+=("$!")
for _ in $(seq 100); do rosservice list 2>/dev/null | grep -q /fragg_map/get_stats && break; sleep 0.2; done
# Kept alive past the bag's end (an exiting player can lose its last message); the probe waits
# for the node to hold every cloud of it.
rosbag play --clock -q -r 0.5 --keep-alive "$first" >>"$log" 2>&1 &
player_pid=$!
FRAGG_STARTED+=("$player_pid")
# shellcheck disable=SC2086
/usr/bin/python3 "$FRAGG_REPO/scripts/frontier_service_probe.py" --scans "$scans" \
  --more-bag "$rest" --k "$k" --box-edge "$box_edge" --box-center $center \
  --before-queries "kill -INT $player_pid" | tee "$out/probe.json"
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); commit $(git -C "$FRAGG_REPO" rev-parse --short HEAD)"
