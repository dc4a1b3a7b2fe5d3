#!/usr/bin/env bash
# The main job: builds maps from the real scans in
# ../shared/data/real with `fragg_map build`, prints their statistics, renders them to PNG
# (top-down height image and a horizontal slice) and exports them as OctoMap .bt files; then
# maps the simulator's smoke workload and scores it against the scene's ground truth; then runs
# the ROS map server nodelet on the smoke bag (scripts/demo_ros.sh).
# Installs the missing Debian packages and builds the catkin workspace (<checkout>_ws) first.
# Outputs go to out/demo/ under the repository root.
set -euo pipefail
# First-run speed: CUDA kernels for the GPU present only, none without a GPU (common.sh).
FRAGG_CUDA="${FRAGG_CUDA:-machine}"
# and the sources compiled in unity batches (fewer, larger translation units: less CPU).
FRAGG_UNITY="${FRAGG_UNITY:-ON}"
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
FRAGG_DEPS_ARGS=(--demo)  # no test, format or benchmark packages: the demo builds no tests

fragg_usage() {
  echo "usage: bash scripts/demo.sh [options]"
  fragg_usage_common
  echo "  env FRAGG_DATA  real data folder (default: ../shared/data/real beside the checkout)"
}
fragg_parse_common "$@"

data="${FRAGG_DATA:-$FRAGG_REPO/../shared/data/real}"
for input in "$data/slambook2_ch5_rgbd/pose.txt" "$data/small_gicp_pair/target.ply"; do
  if [ ! -e "$input" ]; then
    echo "demo: $input not found: the real data belongs in ../shared/data/real beside the" \
      "checkout (or set FRAGG_DATA)" >&2
    exit 1
  fi
done
data="$(cd "$data" && pwd -P)"
rgbd="$data/slambook2_ch5_rgbd"
velodyne="$data/small_gicp_pair/target.ply"

fragg_install_deps
fragg_octomap_msgs_standin  # octomap_binary / octomap_full without a packaged octomap_msgs
fragg_build_demo
fragg="$FRAGG_WS/devel/lib/fragg_map/fragg_map"
out="$FRAGG_REPO/out/demo"
mkdir -p "$out"

run() {
  printf '$ %s\n' "$*" | sed "s|$FRAGG_WS/devel/lib/fragg_map/||g; s|$FRAGG_REPO/||g"
  "$@"
}

# 1. Five Kinect v1 RGB-D frames (NYU Depth v2) at 2 cm. Their world frame is the optical
#    frame of the first camera pose (z forward, y down): the "top" view looks along the
#    optical axis, a front view coloured by depth, and slices are planes at a fixed depth.
fragg_step "RGB-D frames: $rgbd"
run "$fragg" build "$rgbd" -o "$out/rgbd.fgm" --resolution 0.02
run "$fragg" stats "$out/rgbd.fgm"
run "$fragg" render "$out/rgbd.fgm" -o "$out/rgbd_top.png" --view top
run "$fragg" render "$out/rgbd.fgm" -o "$out/rgbd_slice_z3.png" --view slice --z 3.0
run "$fragg" export "$out/rgbd.fgm" --format bt -o "$out/rgbd.bt"

# 2. One Velodyne scan (32 beams, sensor at the origin, z up) at 5 cm. Returns beyond 40 m
#    become free-only rays cut at 40 m. The slice at the sensor's height is a floor plan.
fragg_step "Velodyne scan: $velodyne"
run "$fragg" build "$velodyne" -o "$out/velodyne.fgm" --max-range 40
run "$fragg" stats "$out/velodyne.fgm"
run "$fragg" render "$out/velodyne.fgm" -o "$out/velodyne_top.png" --view top
run "$fragg" render "$out/velodyne.fgm" -o "$out/velodyne_slice_z0.png" --view slice --z 0.0
run "$fragg" export "$out/velodyne.fgm" --format bt -o "$out/velodyne.bt"
# The exported OctoMap file reads back (through liboctomap).
run "$fragg" stats "$out/velodyne.bt"

# 3. The simulator's smoke workload (made by the build: 10 scans of a 16-beam LiDAR in the
#    campus scene): from the bag (poses from its /tf: drifting odometry) and from the KITTI
#    folder (ground-truth poses), whose map is scored against the scene's ground truth.
smoke="$FRAGG_WS/build/workloads"
fragg_step "simulated LiDAR (smoke workload): $smoke"
run "$fragg" build "$smoke/smoke.bag" -o "$out/smoke_bag.fgm" --max-range 30
run "$fragg" build "$smoke/smoke" -o "$out/smoke.fgm" --max-range 30
run "$fragg" eval "$out/smoke.fgm" --scene "$smoke/campus.obj"
run "$fragg" render "$out/smoke.fgm" -o "$out/smoke_top.png" --view top

# 4. The ROS map server (fragg_map/MapServerNodelet) on the smoke bag, headless: a master on
#    loopback, the nodelet, the bag; the map saved through /fragg_map/save_map, rendered, and
#    compared with `fragg_map build` on the same bag. scripts/demo_ros.sh stops what it starts.
bash "$FRAGG_REPO/scripts/demo_ros.sh" --no-deps --no-build --ws "$FRAGG_WS" --jobs "$FRAGG_JOBS" --out "$out"

fragg_step "outputs ($(fragg_elapsed))"
cat <<EOF
Maps, images and OctoMap files are in $out:
  rgbd.fgm      velodyne.fgm       fragg_map maps (fragg_map stats / render / export / compare)
  rgbd.bt       velodyne.bt        OctoMap binary trees (octovis, octomap_server, fragg_map stats)
  rgbd_top.png  velodyne_top.png   height images; unknown space is dark
  rgbd_slice_z3.png  velodyne_slice_z0.png   slices: free, occupied and unknown in distinct colours
  smoke.fgm  smoke_bag.fgm  smoke_top.png      the simulated campus (ground truth / odometry poses)
  node_smoke.fgm  node_smoke_top.png           the same bag mapped by the ROS nodelet (save_map)
The CLI: $fragg --help
EOF
