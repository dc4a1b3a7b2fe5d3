#!/usr/bin/env bash
# The ROS part of the demo: starts a ROS master on loopback (a free port), the map server
# nodelet and the smoke bag (launch/demo.launch, headless), waits until every scan is
# inserted, saves the map through /fragg_map/save_map, renders it to PNG, checks it against
# `fragg_map build` on the same bag, reads the map back with octomap_server's octomap_saver (a
# GetOctomap client), and stops everything it started.
# Usage: bash scripts/demo_ros.sh [--out DIR] [--no-build] [common options]
# (scripts/demo.sh runs it after building the workspace: --no-deps --no-build, the same --ws.)
set -euo pipefail
# First-run speed: CUDA kernels for the GPU present only, none without a GPU (common.sh).
FRAGG_CUDA="${FRAGG_CUDA:-machine}"
# and the sources compiled in unity batches (fewer, larger translation units: less CPU).
FRAGG_UNITY="${FRAGG_UNITY:-ON}"
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
FRAGG_DEPS_ARGS=(--demo)  # no test, format or benchmark packages: the demo builds no tests

out="$FRAGG_REPO/out/demo"
build=1
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --no-build) build=0; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
fragg_usage() {
  echo "usage: bash scripts/demo_ros.sh [--out DIR] [--no-build]"
  fragg_usage_common
  echo "  --no-build    the workspace is built already (demo.sh)"
}
fragg_parse_common "${args[@]+"${args[@]}"}"
fragg_install_deps
fragg_octomap_msgs_standin  # octomap_binary / octomap_full without a packaged octomap_msgs
[ "$build" -eq 0 ] || fragg_build_demo
mkdir -p "$out"
out="$(cd "$out" && pwd -P)"
fragg="$FRAGG_WS/devel/lib/fragg_map/fragg_map"
bag="$FRAGG_WS/build/workloads/smoke.bag"

port="$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://127.0.0.1:$port"
set +u
# shellcheck disable=SC1091
source "$FRAGG_WS/devel/setup.bash"
set -u

launch_pid=""
stop() {
  if [ -n "$launch_pid" ] && kill -0 "$launch_pid" 2>/dev/null; then
    kill -INT "$launch_pid" 2>/dev/null || true  # roslaunch stops the node and its master
    for _ in $(seq 50); do kill -0 "$launch_pid" 2>/dev/null || break; sleep 0.2; done
    kill -TERM "$launch_pid" 2>/dev/null || true
  fi
}
trap stop EXIT

fragg_step "ROS map server on the smoke bag (master on 127.0.0.1:$port)"
log="$out/demo_ros.log"
# Played at a quarter of its speed with a deep queue, so every scan is inserted (with the
# default queue the oldest clouds are dropped, and counted, when insertion falls behind). The
# file services write under file_root: out/demo here.
roslaunch "$FRAGG_REPO/launch/demo.launch" bag:="$bag" cloud:=/points rate:=0.25 queue_size:=20 \
  config:="$FRAGG_REPO/config/default.yaml" file_root:="$out" >"$log" 2>&1 &
launch_pid=$!
echo "roslaunch (pid $launch_pid), log: $log"

stats() { rosservice call /fragg_map/get_stats 2>/dev/null; }
deadline=$((SECONDS + 120))
until stats | grep -Eq '^  scans: 10$'; do
  if [ $SECONDS -ge $deadline ] || ! kill -0 "$launch_pid" 2>/dev/null; then
    echo "demo_ros: the map server did not insert the 10 scans in time; see $log" >&2
    stats >&2 || true
    exit 1
  fi
  sleep 1
done
stats | grep -E '^  (backend|scans|points|dropped_clouds|insertion_ms_mean|known_voxels|host_bytes):'
rosservice call /fragg_map/save_map "path: 'node_smoke.fgm'"  # relative: under file_root
# octomap_server's own client reads the map through GetOctomap (the octomap_binary service):
# octomap_saver where octomap_server is installed; scripts/octomap_saver.py (the same call, the
# same .bt) where it is not (Debian packages no octomap_server).
saver=(/usr/bin/python3 "$FRAGG_REPO/scripts/octomap_saver.py")
if real="$(catkin_find --first-only octomap_server octomap_saver 2>/dev/null)" &&
  [ -x "$real" ]; then
  saver=("$real")
fi
if ! (cd "$out" && timeout 60 "${saver[@]}" node_smoke.bt) >"$out/octomap_saver.log" 2>&1; then
  cat "$out/octomap_saver.log" >&2
  echo "demo_ros: octomap_saver could not read the node's map; see $log" >&2
  exit 1
fi
stop

fragg_step "the node's map"
"$fragg" stats "$out/node_smoke.fgm"
"$fragg" render "$out/node_smoke.fgm" -o "$out/node_smoke_top.png" --view top
# The node keeps its scans (keep_scans, default true) as float32 points as received, so its
# map is the map of the received clouds: the same as `fragg_map build` with its defaults, with
# or without --keep-scans. Any cell that differs is an error.
same_map() {
  "$fragg" compare "$1" "$2"
  "$fragg" compare "$1" "$2" --json | /usr/bin/python3 -c '
import json, sys
c = json.load(sys.stdin)
if c["known_in_either"] == 0 or c["agreeing"] != c["known_in_either"]:
    sys.exit("demo_ros: the maps differ in %d of %d cells" %
             (c["known_in_either"] - c["agreeing"], c["known_in_either"]))'
}
"$fragg" build "$bag" -o "$out/cli_smoke.fgm" --topic /points --frame map >/dev/null
same_map "$out/cli_smoke.fgm" "$out/node_smoke.fgm"
"$fragg" build "$bag" -o "$out/cli_smoke_kept.fgm" --topic /points --frame map --keep-scans \
  >/dev/null
same_map "$out/cli_smoke_kept.fgm" "$out/node_smoke.fgm"

fragg_step "octomap_saver read the node's map: $(basename "${saver[-1]}") node_smoke.bt"
grep -v '^\[' "$out/octomap_saver.log" || true
"$fragg" stats "$out/node_smoke.bt"
# The .bt holds what an OctoMap holds (occupied iff p >= 0.5, every observed cell known): the
# same cells as the node's own save_map under that rule.
"$fragg" compare "$out/node_smoke.fgm" "$out/node_smoke.bt" --octomap-threshold
"$fragg" compare "$out/node_smoke.fgm" "$out/node_smoke.bt" --octomap-threshold --json |
  /usr/bin/python3 -c '
import json, sys
c = json.load(sys.stdin)
if c["known_in_either"] == 0 or c["agreeing"] != c["known_in_either"]:
    sys.exit("demo_ros: the map octomap_saver wrote and the saved map differ in %d of %d cells" %
             (c["known_in_either"] - c["agreeing"], c["known_in_either"]))'

fragg_step "outputs"
cat <<EOT
In $out:
  node_smoke.fgm      the map the nodelet built from smoke.bag, saved through /fragg_map/save_map
  node_smoke_top.png  its top-down height image
  cli_smoke.fgm       fragg_map build on the same bag (compared above: the same map)
  cli_smoke_kept.fgm  the same with --keep-scans (the same map too)
  node_smoke.bt       the node's map as octomap_saver wrote it (GetOctomap: octomap_binary)
  demo_ros.log        roslaunch's log
EOT
