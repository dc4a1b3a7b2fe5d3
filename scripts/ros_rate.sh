#!/usr/bin/env bash
# The sustained cloud rate of the map server (CPU backend): plays a bag made from a KITTI
# folder (W1 by default, scripts/make_workloads.sh) into the nodelet at each rate of --rates
# clouds per second, one fresh node per rate, and reads ~get_stats once the bag is over: a
# rate is kept up with when no cloud was dropped from the queue. Prints one markdown row per
# rate. Starts its own master on a free loopback port and stops everything it started.
# Usage: bash scripts/ros_rate.sh [--workload DIR] [--scans N] [--resolution M]
#          [--max-range M] [--rates "1 2 3"] [--queue-size N] [--markers] [--marker-rate HZ]
#          [--map-rate HZ] [--unpaced] [--no-build] [--out DIR] [common options]
#   --markers       subscribe to occupied_cells_vis_array (rostopic hz, raw bytes) so the node
#                   builds and sends its markers; without it nobody subscribes and it does not
#   --marker-rate   the node's marker_rate parameter (0: an update after every cloud)
#   --map-rate      the node's map_rate parameter (whole-map outputs; default.yaml's when absent)
#   --unpaced       the node's paced_outputs false (throttled updates whole when due)
#   --no-build      use the workspace as it is (no catkin build first)
# The node inherits this shell's environment (GLIBC_TUNABLES, OMP_WAIT_POLICY: the launch files
# set them, this script does not).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

workload="${FRAGG_WORKLOADS:-$HOME/.cache/fragg_map/workloads}/w1_lidar360"
scans=100 resolution=0.05 max_range=30 rates="1 2 3" queue_size=5 markers=0 marker_rate=0
map_rate="" build=1 paced=
out="$FRAGG_REPO/out/ros_rate"
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --workload) workload="$2"; shift 2 ;;
    --scans) scans="$2"; shift 2 ;;
    --resolution) resolution="$2"; shift 2 ;;
    --max-range) max_range="$2"; shift 2 ;;
    --rates) rates="$2"; shift 2 ;;
    --queue-size) queue_size="$2"; shift 2 ;;
    --markers) markers=1; shift ;;
    --marker-rate) marker_rate="$2"; shift 2 ;;
    --map-rate) map_rate="$2"; shift 2 ;;
    --unpaced) paced=false; shift ;;
    --no-build) build=0; shift ;;
    --out) out="$2"; shift 2 ;;
    *) args+=("$1"); shift ;;
  esac
done
fragg_usage() {
  sed -n '7,17p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
  fragg_usage_common
}
fragg_parse_common "${args[@]+"${args[@]}"}"
if [ ! -f "$workload/poses.txt" ]; then
  echo "ros_rate: no KITTI folder at $workload (bash scripts/make_workloads.sh --only w1)" >&2
  exit 1
fi
if [ "$build" = 1 ]; then
  fragg_install_deps
  fragg_build_ws >/dev/null
fi
mkdir -p "$out"
out="$(cd "$out" && pwd -P)"

bag="$out/$(basename "$workload")_$scans.bag"
[ -f "$bag" ] || /usr/bin/python3 "$FRAGG_REPO/scripts/kitti_to_bag.py" "$workload" "$bag" \
  --scans "$scans"
# The bag's own rate (clouds per second of sensor time): rosbag play -r scales it.
bag_hz="$(/usr/bin/python3 -c 'import sys
t = [float(l) for l in open(sys.argv[1]) if l.strip()][:int(sys.argv[2])]
print((len(t) - 1) / (t[-1] - t[0]))' "$workload/times.txt" "$scans")"

trap fragg_stop_started EXIT
log="$out/ros_rate.log"
: >"$log"
fragg_start_master "$log"
rosparam set /use_sim_time true

# One field of a `rosservice call .../get_stats` answer (0 when absent).
field() {
  local v
  v="$(printf '%s\n' "$1" | sed -n "s/^  $2: //p")"
  echo "${v:-0}"
}

cat <<EOT
$(basename "$workload"), $scans clouds of the bag ($bag_hz Hz recorded), ${resolution} m, max range ${max_range} m, CPU backend, queue_size $queue_size, markers $([ "$markers" -eq 1 ] && echo "subscribed, marker_rate $marker_rate" || echo "not subscribed")
| clouds/s | inserted | dropped (queue full) | insertion ms mean | p99 | marker arrays received |
|---:|---:|---:|---:|---:|---:|
EOT
for rate in $rates; do
  rosparam delete /fragg_map >/dev/null 2>&1 || true
  rosparam load "$FRAGG_REPO/config/default.yaml" /fragg_map
  rosparam set /fragg_map/resolution "$resolution"
  rosparam set /fragg_map/backend cpu
  rosparam set /fragg_map/sensor_model/max_range "$max_range"
  rosparam set /fragg_map/queue_size "$queue_size"
  rosparam set /fragg_map/marker_rate "$marker_rate"
  [ -z "$map_rate" ] || rosparam set /fragg_map/map_rate "$map_rate"
  [ -z "$paced" ] || rosparam set /fragg_map/paced_outputs "$paced"
  # Unlatched, as the figures in docs/benchmarks.md were measured (latched, the default since
  # issue 16, builds every output after every cloud even without subscribers).
  rosparam set /fragg_map/latch false
  rosrun nodelet nodelet standalone fragg_map/MapServerNodelet __name:=fragg_map \
    cloud_in:=/points >>"$log" 2>&1 &
  node_pid=$!
  FRAGG_STARTED+=("$node_pid")
  hz_pid=""
  if [ "$markers" -eq 1 ]; then
    rostopic hz /occupied_cells_vis_array >"$out/hz_$rate.log" 2>&1 &
    hz_pid=$!
    FRAGG_STARTED+=("$hz_pid")
  fi
  for _ in $(seq 100); do rosservice list 2>/dev/null | grep -q /fragg_map/get_stats && break; sleep 0.2; done
  factor="$(/usr/bin/python3 -c "print($rate / $bag_hz)")"
  rosbag play --clock -d 2 -r "$factor" "$bag" >>"$log" 2>&1
  # The bag is over: wait for the queue to drain (inserted + dropped = every cloud).
  deadline=$((SECONDS + 600))
  while :; do
    s="$(rosservice call /fragg_map/get_stats 2>/dev/null || true)"
    done_clouds=$(($(field "$s" scans) + $(field "$s" dropped_clouds)))
    [ "$done_clouds" -ge "$scans" ] && break
    if [ $SECONDS -ge $deadline ] || ! kill -0 "$node_pid" 2>/dev/null; then
      echo "ros_rate: the node did not take the $scans clouds in time; see $log" >&2
      exit 1
    fi
    sleep 1
  done
  arrays="-"
  if [ -n "$hz_pid" ]; then
    sleep 2  # pending markers (marker_rate) go out within a period
    fragg_stop_pid "$hz_pid" INT
    arrays="$(sed -n 's/.*average rate.*//p; s/^.*min: .*window: \([0-9]*\).*$/\1/p' \
      "$out/hz_$rate.log" | tail -n 1)"
  fi
  printf '| %s | %s | %s | %.0f | %.0f | %s |\n' "$rate" "$(field "$s" scans)" \
    "$(field "$s" dropped_queue_full)" "$(field "$s" insertion_ms_mean)" \
    "$(field "$s" insertion_ms_p99)" "${arrays:--}"
  fragg_stop_pid "$node_pid" INT
done
