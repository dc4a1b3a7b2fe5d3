#!/usr/bin/env bash
# fragg_map beside the real octomap_server, as a user switching would: the same bag of real
# scans, the same octomap_server YAML, once through octomap_server_node and once through
# launch/octomap_compat.launch. For each it records the topics, services and parameters under
# the node, saves the map with octomap_server's own client (octomap_saver: GetOctomap on
# octomap_full and octomap_binary), and compares the two maps cell by cell (fragg_map compare
# --octomap-threshold: the share of cells either map knows that agree).
#   bash scripts/side_by_side.sh [--mirror DIR] [--ws DIR]
# SBS_ONLY="rgbd nebula" runs those bags only (velodyne_pair, nebula, rgbd), appending to the
# summary.
# Needs the workspace built (scripts/build.sh); builds octomap_server first when it is not
# there yet (scripts/side_by_side_build.sh, ~6 min on 2 cores). Everything it writes lies
# under out/side_by_side/ (git-ignored); the summary is out/side_by_side/results.md.
# Bags: made from ../shared/data/real: the small_gicp Velodyne pair (test/io/make_test_bag.py),
# the six nebula single scans (written here) and the slambook2 RGB-D frames
# (test/rostest/make_rgbd_bag.py).
set -euo pipefail
source "$(dirname "$0")/common.sh"

MIRROR_ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --mirror) MIRROR_ARGS=(--mirror "${2:?--mirror needs a folder}"); shift 2 ;;
    --ws) FRAGG_WS="${2:?--ws needs a folder}"; shift 2 ;;
    *) echo "side_by_side.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done

OUT="$FRAGG_REPO/out/side_by_side"
OWS="$OUT/octomap_ws"
DATA="${FRAGG_DATA:-$FRAGG_REPO/../shared/data/real}"
mkdir -p "$OUT/run"
[ -x "$OWS/devel/lib/octomap_server/octomap_server_node" ] ||
  bash "$FRAGG_REPO/scripts/side_by_side_build.sh" "${MIRROR_ARGS[@]}"
set +u  # the setup files read unset variables
# shellcheck disable=SC1091
source "$FRAGG_WS/devel/setup.bash"
set -u
export LD_LIBRARY_PATH="$OWS/devel/lib:${LD_LIBRARY_PATH:-}"
SERVER="$OWS/devel/lib/octomap_server/octomap_server_node"
SAVER="$OWS/devel/lib/octomap_server/octomap_saver"
CLI="$FRAGG_WS/devel/lib/fragg_map/fragg_map"

port="$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://127.0.0.1:$port" ROS_HOME="$OUT/run/ros_home"
pids=()
stop_all() {
  local p
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.2; done
    kill -TERM "$p" 2>/dev/null || true
  done
  pids=()
}
trap stop_all EXIT

rosmaster --core -p "$port" >"$OUT/run/master.log" 2>&1 &
master_pid=$!
for _ in $(seq 50); do rostopic list >/dev/null 2>&1 && break; sleep 0.2; done

# bag topic yaml name: one run of `what` (octomap_server | fragg_map) on the bag.
run_one() {
  local what="$1" bag="$2" topic="$3" yaml="$4" name="$5" dir="$OUT/run/$5/$1"
  mkdir -p "$dir"
  rosparam delete /octomap_server >/dev/null 2>&1 || true
  rosparam set /use_sim_time true
  if [ "$what" = octomap_server ]; then
    rosparam load "$yaml" /octomap_server
    "$SERVER" cloud_in:="$topic" __name:=octomap_server >"$dir/node.log" 2>&1 &
  else
    roslaunch "$FRAGG_REPO/launch/octomap_compat.launch" params:="$yaml" cloud:="$topic" \
      backend:=cpu >"$dir/node.log" 2>&1 &
  fi
  local node_pid=$!
  pids=("$node_pid")
  # Up to 2 minutes. The list is read whole first: `rosservice list | grep -q` fails under
  # pipefail when grep exits before rosservice has written everything.
  has_octomap_full() { rosservice list 2>/dev/null | grep -c '^/octomap_full$' >/dev/null; }
  local deadline=$((SECONDS + 120))
  until has_octomap_full || [ $SECONDS -ge $deadline ]; do sleep 0.5; done
  if ! has_octomap_full; then
    echo "$what did not come up on $name (see $dir/node.log)" >&2
    stop_all
    return 1
  fi
  /usr/lib/rosbag/play --clock -d 2 -r 0.25 "$bag" >"$dir/play.log" 2>&1
  sleep 4  # the last cloud's insertion
  rostopic list 2>/dev/null | grep -v -E '^/(rosout|rosout_agg|clock|tf|tf_static)$' | sort >"$dir/topics.txt"
  rosservice list 2>/dev/null | grep -E '^/octomap' | grep -v -E '/(get_loggers|set_logger_level)$' |
    sort >"$dir/services.txt"
  rosparam list /octomap_server 2>/dev/null | sort >"$dir/params.txt"
  # The type and md5sum each publisher and service announces (connection headers).
  timeout 30 /usr/bin/python3 - >"$dir/types.txt" 2>"$dir/types.log" <<'PY' || true
import rospy, rosservice, threading
rospy.init_node("side_by_side_types", anonymous=True, disable_signals=True)
got = {}
done = threading.Event()
def keep(topic):
    def cb(msg):
        h = msg._connection_header
        got[topic] = (h["type"], h["md5sum"])
        if len(got) == 2: done.set()
    return cb
subs = [rospy.Subscriber(t, rospy.AnyMsg, keep(t)) for t in ("/octomap_binary", "/octomap_full")]
done.wait(20)
for t in ("/octomap_binary", "/octomap_full"):
    print(t, *got.get(t, ("none", "-")))
for s in ("/octomap_binary", "/octomap_full"):
    h = rosservice.get_service_headers(s, rosservice.get_service_uri(s))
    print(s, "(service)", h.get("type", "?"), h.get("md5sum", "?"))
PY
  (cd "$dir" && timeout 60 "$SAVER" -f map.ot >"$dir/saver_full.log" 2>&1 &&
    timeout 60 "$SAVER" map.bt >"$dir/saver_binary.log" 2>&1) ||
    echo "octomap_saver failed against $what (see $dir/saver_*.log)" >&2
  stop_all
}

# name bag topic yaml: both servers on one bag, then the comparison.
compare_bag() {
  local name="$1" bag="$2" topic="$3" yaml="$4"
  case " ${SBS_ONLY:-$name} " in *" $name "*) ;; *) return 0 ;; esac
  run_one octomap_server "$bag" "$topic" "$yaml" "$name"
  run_one fragg_map "$bag" "$topic" "$yaml" "$name"
  local a="$OUT/run/$name/octomap_server" b="$OUT/run/$name/fragg_map"
  {
    echo "### $name"
    echo
    echo "bag: $(basename "$bag"), topic $topic, YAML: $(tr '\n' ' ' <"$yaml")"
    echo
    echo '```'
    for f in map.ot map.bt; do
      if [ -s "$a/$f" ] && [ -s "$b/$f" ]; then
        echo "octomap_saver $f, octomap_server vs fragg_map (compare --octomap-threshold):"
        "$CLI" compare "$a/$f" "$b/$f" --octomap-threshold | grep -E 'either|both' |
          awk '{ print } /known in either/ { printf "union agreement: %d of %d cells, %.5f %%\n", $8, $4, 100 * $8 / $4 }' || true
      else
        echo "octomap_saver $f: missing (octomap_server: $(stat -c %s "$a/$f" 2>/dev/null || echo none), fragg_map: $(stat -c %s "$b/$f" 2>/dev/null || echo none))"
      fi
    done
    # octomap_saver prunes the tree it received to its max-likelihood states before writing a
    # .bt, so the files are equal where the cells are, whatever tree each node sent (the
    # "Map received" counts below: octomap_server sends its log-odds tree).
    if [ -s "$a/map.bt" ] && cmp -s "$a/map.bt" "$b/map.bt"; then
      echo "octomap_saver map.bt: byte-identical ($(stat -c %s "$a/map.bt") bytes)"
    else
      echo "octomap_saver map.bt: the files differ"
    fi
    for who in octomap_server fragg_map; do
      echo "octomap_saver (GetOctomap) against $who: $(grep -h -o 'Map received.*' "$OUT/run/$name/$who"/saver_*.log |
        sed 's/\x1b\[[0-9;]*m//g' | tr '\n' ' ')"
    done
    for what in topics services params types; do
      if diff -q "$a/$what.txt" "$b/$what.txt" >/dev/null; then
        echo "$what: the same ($(wc -l <"$a/$what.txt") lines)"
      else
        echo "$what: differ (< octomap_server, > fragg_map):"
        diff "$a/$what.txt" "$b/$what.txt" | grep -E '^[<>]' || true
      fi
    done
    echo '```'
    echo
  } >>"$OUT/results.md"
}

bags="$OUT/bags"
mkdir -p "$bags"
[ -s "$bags/velodyne_pair.bag" ] ||
  /usr/bin/python3 "$FRAGG_REPO/test/io/make_test_bag.py" "$bags/velodyne_pair.bag" "$DATA/small_gicp_pair" >/dev/null
# octomap_server reads clouds through PCL, which takes float32 x y z only ("Failed to find
# match for field"): the pair's float64 cloud is written again as float32 (the same values
# rounded, as fragg_map rounds them when it reads the bag), layout and NaNs kept, for both.
[ -s "$bags/velodyne_pair_f32.bag" ] || /usr/bin/python3 - "$bags/velodyne_pair.bag" "$bags/velodyne_pair_f32.bag" <<'PY'
import struct, sys
import rosbag
from sensor_msgs.msg import PointCloud2, PointField
with rosbag.Bag(sys.argv[1]) as src, rosbag.Bag(sys.argv[2], "w") as dst:
    for topic, msg, t in src.read_messages():
        if msg._type == "sensor_msgs/PointCloud2" and any(
                f.name == "x" and f.datatype == PointField.FLOAT64 for f in msg.fields):
            off = {f.name: f.offset for f in msg.fields}
            fmt = (">" if msg.is_bigendian else "<") + "d"
            data = bytearray()
            for row in range(msg.height):
                for col in range(msg.width):
                    base = row * msg.row_step + col * msg.point_step
                    data += struct.pack("<fff", *(struct.unpack_from(fmt, msg.data, base + off[a])[0]
                                                  for a in "xyz"))
            out = PointCloud2(header=msg.header, height=msg.height, width=msg.width,
                              fields=[PointField(a, 4 * i, PointField.FLOAT32, 1)
                                      for i, a in enumerate("xyz")],
                              is_bigendian=False, point_step=12, row_step=12 * msg.width,
                              data=bytes(data), is_dense=False)
            dst.write(topic, out, t)
        else:
            dst.write(topic, msg, t)
PY
# The six nebula single scans (VLP-16 ... VLS-128), one cloud each, 3 s apart, sensor at the
# map origin (/tf_static map -> lidar): x y z of their binary PCDs as float32.
[ -s "$bags/nebula.bag" ] || /usr/bin/python3 - "$DATA/nebula_single_scans" "$bags/nebula.bag" <<'PY'
import glob, os, struct, sys
import rosbag, rospy
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import PointCloud2, PointField
from tf2_msgs.msg import TFMessage
with rosbag.Bag(sys.argv[2], "w") as bag:
    tf = TransformStamped()
    tf.header.frame_id, tf.child_frame_id = "map", "lidar"
    tf.header.stamp = rospy.Time(0.5)
    tf.transform.rotation.w = 1.0
    bag.write("/tf_static", TFMessage([tf]), rospy.Time(0.5))
    for i, path in enumerate(sorted(glob.glob(os.path.join(sys.argv[1], "*.pcd")))):
        raw = open(path, "rb").read()
        end = raw.index(b"DATA binary\n") + len(b"DATA binary\n")
        head = dict((l.split(" ", 1) + [""])[:2] for l in raw[:end].decode().splitlines())
        sizes = [int(v) * int(c) for v, c in zip(head["SIZE"].split(), head["COUNT"].split())]
        step, n = sum(sizes), int(head["POINTS"])
        names = head["FIELDS"].split()
        assert names[:3] == ["x", "y", "z"] and head["TYPE"].split()[:3] == ["F"] * 3, path
        body = raw[end:end + step * n]
        xyz = b"".join(body[k * step:k * step + 12] for k in range(n))
        t = rospy.Time(1.0 + 3.0 * i)
        msg = PointCloud2(height=1, width=n, is_bigendian=False, point_step=12, row_step=12 * n,
                          fields=[PointField(a, 4 * j, PointField.FLOAT32, 1)
                                  for j, a in enumerate("xyz")], data=xyz, is_dense=False)
        msg.header.frame_id, msg.header.stamp = "lidar", t
        bag.write("/points", msg, t)
PY
[ -s "$bags/rgbd.bag" ] ||
  /usr/bin/python3 "$FRAGG_REPO/test/rostest/make_rgbd_bag.py" "$bags/rgbd.bag" "$DATA/slambook2_ch5_rgbd" >/dev/null

cat >"$bags/velodyne.yaml" <<'EOF'
frame_id: map
resolution: 0.1
sensor_model: {max_range: 20.0}
EOF
cat >"$bags/rgbd.yaml" <<'EOF'
frame_id: map
resolution: 0.05
sensor_model: {max_range: 6.0}
EOF

# Every run starts with a header naming the commit (a run of SBS_ONLY bags appends its own).
commit="$(git -C "$FRAGG_REPO" rev-parse --short HEAD)"
[ -z "$(git -C "$FRAGG_REPO" status --porcelain --untracked-files=no)" ] ||
  commit="$commit + uncommitted changes"
header="## octomap_server (octomap_mapping efa61ca) beside fragg_map ($commit), $(date -u '+%F %H:%M UTC')"
if [ -n "${SBS_ONLY:-}" ]; then
  printf '%s, only: %s\n\n' "$header" "$SBS_ONLY" >>"$OUT/results.md"
else
  printf '%s\n\n' "$header" >"$OUT/results.md"
fi
compare_bag velodyne_pair "$bags/velodyne_pair_f32.bag" /velodyne_points "$bags/velodyne.yaml"
cat >"$bags/nebula.yaml" <<'EOF'
frame_id: map
resolution: 0.1
sensor_model: {max_range: 30.0}
EOF
compare_bag nebula "$bags/nebula.bag" /points "$bags/nebula.yaml"
compare_bag rgbd "$bags/rgbd.bag" /camera/depth_registered/points "$bags/rgbd.yaml"
kill -INT "$master_pid" 2>/dev/null || true
cat "$OUT/results.md"
