#!/usr/bin/env bash
# The map server at sensor rate on the GPU machine (issue 35's goal): the node staged by
# scripts/stage_ros.sh (built with CUDA) fed W1's LiDAR (128 beams x 1,406 columns, ~180,000
# points, config/workloads/w1_lidar360.args) along the campus street, recorded at 10 clouds/s
# sensor time (--clouds clouds, 0.14 m apart, generated on the machine by the staged
# fragg_map_sim: the bag is ~2 GB, too big to carry) and played at --rate clouds/s, with every
# output subscribed (the staged rosbag recorder on occupied and free markers, occupied cloud,
# centres, projected map, frontiers, frontier cells, frustum and ~stats). Prints the card, the
# trace_csv rows by outcome (drops included), and the receive-to-published latency p50/p99
# with each stage's p99, the p99 of the insertion's and outputs' parts and each cloud over
# 20 ms by part (FRAGG_NODE_COMMIT names the staged node's commit: the device's checkout may
# report a stale HEAD). Parameters: config/default.yaml with backend, resolution and
# sensor_model/max_range set, plus any `name:=value` arguments (e.g. marker_rate:=1
# map_rate:=1; publish_free_space:=true adds the free-space markers, huge on a LiDAR map).
# Usage (on the device, in the checkout; .device/ros or .device/ros.tar.xz carried):
#   bash scripts/device_node_rate.sh [--rate HZ] [--clouds N] [--resolution M] [--max-range M]
#     [--backend cuda|cpu|auto] [--azimuth-steps N] [--bag FILE] [--out DIR] [name:=value ...]
# --azimuth-steps: columns a revolution (default 1406: 179,968 points a cloud; 2048: 262,144,
# a 128-beam LiDAR at 2048 columns). FRAGG_ROS_DIR: another staged runtime than .device/ros
# (an older node side by side in one call: the same runtime with its fragg_map binaries).
set -euo pipefail
rate=10 clouds=620 resolution=0.05 max_range=30 backend=cuda bag="" out="${OUT:-/tmp/node_rate}"
azimuth_steps=1406
params=()
while [ $# -gt 0 ]; do
  case "$1" in
    --rate) rate="$2"; shift 2 ;;
    --clouds) clouds="$2"; shift 2 ;;
    --resolution) resolution="$2"; shift 2 ;;
    --max-range) max_range="$2"; shift 2 ;;
    --backend) backend="$2"; shift 2 ;;
    --azimuth-steps) azimuth_steps="$2"; shift 2 ;;
    --bag) bag="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    *:=*) params+=("$1"); shift ;;
    *) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 2 ;;
  esac
done
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)
ros="${FRAGG_ROS_DIR:-$top/.device/ros}"
if [ ! -d "$ros" ]; then
  [ -f "$ros.tar.xz" ] || { echo "device_node_rate: no $ros (bash scripts/stage_ros.sh)" >&2; exit 2; }
  tar -C "$top/.device" -xJf "$ros.tar.xz"
fi
# shellcheck disable=SC1091
source "$ros/env.sh"
mkdir -p "$out"
scratch=$(mktemp -d /tmp/node_rate.XXXXXX)
bag=${bag:-/tmp/w1_street_${clouds}_${azimuth_steps}.bag}
if [ ! -f "$bag" ]; then
  # W1's sensor and seed; 1.4 m/s at 10 Hz keeps --clouds frames (<= 640) on the 90 m street.
  echo "device_node_rate: recording $clouds W1 clouds into $bag"
  fragg_map_sim record "$top/config/scenes/campus.json" --trajectory street --sensor lidar \
    --seed 101 --beams 128 --azimuth-steps "$azimuth_steps" --elevation-min -25 --elevation-max 15 \
    --lidar-max-range 80 --range-noise 0.02 --lidar-dropout 0.0 --speed 1.4 --rate 10 \
    --frames "$clouds" --bag "$bag.part" > "$out/sim.log" 2>&1
  mv "$bag.part" "$bag"
fi
pids=()
cleanup() {
  for pid in "${pids[@]+"${pids[@]}"}"; do kill -TERM "$pid" 2>/dev/null || true; done
  sleep 2
  for pid in "${pids[@]+"${pids[@]}"}"; do kill -KILL "$pid" 2>/dev/null || true; done
  rm -rf "$scratch"
}
trap cleanup EXIT
port=${ROS_MASTER_URI##*:}
rosmaster --core -p "${port%/}" > "$out/master.log" 2>&1 &
pids+=($!)
# Parameters through the master (the staged Python: rosgraph, yaml): default.yaml under
# /fragg_map, then this run's settings; /use_sim_time for the bag's clock.
python3 - "$top/config/default.yaml" "$backend" "$resolution" "$max_range" "$out/trace.csv" \
  "${params[@]+"${params[@]}"}" <<'PY'
import sys, time, yaml, rosgraph.masterapi
m = rosgraph.masterapi.Master("/device_node_rate")
for _ in range(100):
    try:
        m.getPid(); break
    except Exception:
        time.sleep(0.2)
m.setParam("/fragg_map", yaml.safe_load(open(sys.argv[1])))
m.setParam("/use_sim_time", True)
for name, value in [("backend", sys.argv[2]), ("resolution", float(sys.argv[3])),
                    ("sensor_model/max_range", float(sys.argv[4])), ("trace_csv", sys.argv[5])]:
    m.setParam("/fragg_map/" + name, value)
for arg in sys.argv[6:]:
    name, value = arg.split(":=", 1)
    m.setParam("/fragg_map/" + name, yaml.safe_load(value))
PY
# The node's environment as launch/fragg_map.launch sets it unless given (2 MiB pages for the
# large output messages; OpenMP threads that sleep rather than spin beside the node's others).
GLIBC_TUNABLES=${GLIBC_TUNABLES-glibc.malloc.hugetlb=1} OMP_WAIT_POLICY=${OMP_WAIT_POLICY-passive} \
  fragg_map_server __name:=fragg_map cloud_in:=/points > "$out/node.log" 2>&1 &
node_pid=$!
pids+=("$node_pid")
for _ in $(seq 300); do grep -q "map at" "$out/node.log" && break; sleep 0.2; done
grep -q "map at" "$out/node.log" || { echo "device_node_rate: the node did not start" >&2; tail "$out/node.log" >&2; exit 1; }
grep -m1 "map at" "$out/node.log"
# The recorder writes what it receives: split at 1 GB, at most 2 files kept, so that a long run
# at every-cloud output rates (tens of GB) cannot fill the disk.
record -q --split --size 1024 --max-splits 2 -O "$scratch/outputs.bag" \
  /occupied_cells_vis_array /free_cells_vis_array \
  /occupied_cells /octomap_point_cloud_centers /projected_map /frontiers /frontier_cells \
  /frustum /fragg_map/stats > "$out/record.log" 2>&1 &
pids+=($!)
sleep 3
factor=$(python3 -c "print($rate / 10.0)")
play --clock -q -d 2 -r "$factor" "$bag" > "$out/play.log" 2>&1
# Every cloud received has its trace row (inserted, or the count it landed in); wait for them.
for _ in $(seq 600); do
  [ "$(($(wc -l < "$out/trace.csv") - 1))" -ge "$clouds" ] && break
  sleep 0.2
done
sleep 3
kill -INT "$node_pid" 2>/dev/null || true
wait "$node_pid" 2>/dev/null || true
echo "card: $(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1)"
echo "commit: ${FRAGG_NODE_COMMIT:-$(git -C "$top" rev-parse --short HEAD 2>/dev/null)}, W1 street (128 x $azimuth_steps beams), $clouds clouds at $rate/s, $resolution m, max range $max_range m, backend $backend ${params[*]+"${params[*]}"}"
echo "node environment: GLIBC_TUNABLES=${GLIBC_TUNABLES-glibc.malloc.hugetlb=1} OMP_WAIT_POLICY=${OMP_WAIT_POLICY-passive}"
echo "outputs received by the subscriber (the last <= 2 GB kept): $(du -ch "$scratch"/outputs* 2>/dev/null | tail -1 | cut -f1)"
echo "node parameters: default.yaml's marker_rate $(grep -m1 '^marker_rate' "$top/config/default.yaml" | awk '{print $2}'), map_rate $(grep -m1 '^map_rate' "$top/config/default.yaml" | awk '{print $2}') unless given above"
python3 - "$out/trace.csv" "$clouds" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
by = {}
for r in rows:
    by[r["outcome"]] = by.get(r["outcome"], 0) + 1
print("trace rows: %d of %d clouds; by outcome: %s" % (len(rows), int(sys.argv[2]), by))
print("dropped (every outcome but inserted): %d" % (len(rows) - by.get("inserted", 0)))
ok = [r for r in rows if r["outcome"] == "inserted"]
def pct(col, q):
    v = sorted(float(r[col]) for r in ok)
    return v[min(len(v) - 1, int(q * len(v)))] if v else float("nan")
print("receive-to-published ms: p50 %.2f, p99 %.2f, max %.2f" %
      (pct("total_ms", 0.5), pct("total_ms", 0.99), pct("total_ms", 1.0)))
print("p99 by stage ms: queue %.2f, tf %.2f, insert %.2f, publish %.2f" %
      tuple(pct(c, 0.99) for c in ("queue_ms", "tf_ms", "insert_ms", "publish_ms")))
parts = ("lock_wait_ms", "publish_wait_ms", "markers_ms", "map_outputs_ms", "stats_ms")
if ok and all(c in ok[0] for c in parts):
    print("p99 of the parts ms: write-lock wait %.2f, publishers' wait %.2f, markers %.2f, "
          "whole-map outputs %.2f, stats %.2f" % tuple(pct(c, 0.99) for c in parts))
    slow = [(i, r) for i, r in enumerate(rows) if r["outcome"] == "inserted" and float(r["total_ms"]) > 20]
    print("clouds over 20 ms: %d of %d (index: total = queue + tf + insert [lock wait] + publish "
          "[wait, markers, maps, stats])" % (len(slow), len(ok)))
    for i, r in slow[:40]:
        print("  %4d: %7.2f = %.2f + %.2f + %.2f [%.2f] + %.2f [%.2f, %.2f, %.2f, %.2f]" % (
            i, float(r["total_ms"]), float(r["queue_ms"]), float(r["tf_ms"]), float(r["insert_ms"]),
            float(r["lock_wait_ms"]), float(r["publish_ms"]), float(r["publish_wait_ms"]),
            float(r["markers_ms"]), float(r["map_outputs_ms"]), float(r["stats_ms"])))
if ok and "lock_holders" in ok[0]:
    waits = [(i, r) for i, r in enumerate(rows) if r["outcome"] == "inserted" and float(r["lock_wait_ms"]) > 5]
    print("insertions that waited over 5 ms for the write lock: %d (index: wait ms: whom for)" % len(waits))
    for i, r in sorted(waits, key=lambda x: -float(x[1]["lock_wait_ms"]))[:15]:
        print("  %4d: %7.2f: %s" % (i, float(r["lock_wait_ms"]), r["lock_holders"] or "(none named)"))
PY
