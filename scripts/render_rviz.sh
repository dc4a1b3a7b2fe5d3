#!/usr/bin/env bash
# Renders the rviz view of fragg_map (rviz/fragg_map.rviz: block markers, frustum, occupied
# cloud, projected map) to a PNG without a screen: Xvfb, a ROS master on loopback at a free
# port, launch/demo.launch with the smoke bag (or --bag FILE) and rviz, then a screenshot of
# the virtual screen once the bag has played. Stops everything it started. With
# --collision-demo it then asks the server for a collision check (scripts/collision_demo.py: a
# robot box along a path through a wall) and renders rviz/collision.rviz, zoomed on that path,
# to docs/collision_rviz.png.
# Usage: bash scripts/render_rviz.sh [--out docs/rviz.png] [--bag FILE --cloud TOPIC]
#        [--wait S] [--collision-demo] [--no-build] [common options]
#   --no-build   use the workspace as it is (the nodelet built; --bag given or the smoke bag
#                already made)
set -euo pipefail
# First-run speed: CUDA kernels for the GPU present only, none without a GPU (common.sh).
FRAGG_CUDA="${FRAGG_CUDA:-machine}"
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

out=""
bag="" cloud="/points" wait_s=25 collision_demo=0 build=1
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --bag) bag="$2"; shift 2 ;;
    --cloud) cloud="$2"; shift 2 ;;
    --wait) wait_s="$2"; shift 2 ;;
    --collision-demo) collision_demo=1; shift ;;
    --no-build) build=0; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
fragg_usage() {
  echo "usage: bash scripts/render_rviz.sh [--out PNG] [--bag FILE --cloud TOPIC] [--wait S] [--collision-demo] [--no-build]"
  fragg_usage_common
}
fragg_parse_common "${args[@]+"${args[@]}"}"

if [ "$FRAGG_DEPS" -eq 1 ]; then
  fragg_step "Debian packages (+ rviz, Xvfb, imagemagick)"
  bash "$FRAGG_REPO/scripts/install_deps.sh" rviz xvfb xauth imagemagick
fi
[ "$build" -eq 0 ] || fragg_build_ws
rviz_config="$FRAGG_REPO/rviz/fragg_map.rviz"
if [ "$collision_demo" -eq 1 ]; then
  rviz_config="$FRAGG_REPO/rviz/collision.rviz"
  [ -n "$out" ] || out="$FRAGG_REPO/docs/collision_rviz.png"
fi
[ -n "$out" ] || out="$FRAGG_REPO/docs/rviz.png"
[ -n "$bag" ] || bag="$FRAGG_WS/build/workloads/smoke.bag"
bag="$(cd "$(dirname "$bag")" && pwd -P)/$(basename "$bag")"
mkdir -p "$(dirname "$out")"

# A free display and a free port, so that a running master or X server is left alone.
display=77
while [ -e "/tmp/.X11-unix/X$display" ] || [ -e "/tmp/.X$display-lock" ]; do
  display=$((display + 1))
done
port="$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://127.0.0.1:$port" DISPLAY=":$display" LIBGL_ALWAYS_SOFTWARE=1

pids=()
cleanup() {
  local pid
  for pid in "${pids[@]+"${pids[@]}"}"; do
    kill -INT "$pid" 2>/dev/null || true
  done
  sleep 3
  for pid in "${pids[@]+"${pids[@]}"}"; do
    kill -TERM "$pid" 2>/dev/null || true
  done
}
trap cleanup EXIT

fragg_step "Xvfb $DISPLAY, master on port $port"
Xvfb "$DISPLAY" -screen 0 1024x768x24 >/dev/null 2>&1 &
pids+=("$!")
set +u
# shellcheck disable=SC1091
source "$FRAGG_WS/devel/setup.bash"
set -u
log="$(mktemp -d)/demo.log"
roslaunch "$FRAGG_REPO/launch/demo.launch" bag:="$bag" cloud:="$cloud" rviz:=true \
  rviz_config:="$rviz_config" \
  >"$log" 2>&1 &
pids=("$!" "${pids[@]}")  # the launch first: it stops rviz, the node and the master
fragg_step "playing $(basename "$bag"), rendering for ${wait_s} s (log: $log)"
sleep "$wait_s"
if [ "$collision_demo" -eq 1 ]; then
  fragg_step "collision check (scripts/collision_demo.py)"
  /usr/bin/python3 "$FRAGG_REPO/scripts/collision_demo.py"
  sleep 5
fi
import -window root "$out"
# The 3-D view only (rviz/collision.rviz's window layout: docks left and right).
[ "$collision_demo" -eq 0 ] || convert "$out" -crop 366x606+365+64 +repage "$out"
echo "render_rviz: wrote $out"
