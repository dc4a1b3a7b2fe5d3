#!/usr/bin/env bash
# Issue 34's figures before and after, side by side in one call on the GPU machine (plain CMake,
# no ROS): builds a baseline source tree and this one, then on W1 (5 cm, 30 m) runs for each:
# the frontier benchmark on the CUDA and the CPU backend (incremental update per scan, full
# recompute, gains of 1,000 viewpoints), the collision benchmark (100,000 box poses, a mesh of
# 4,900 triangles at 1,000 poses; CPU, CUDA, and this tree's CUDA map read through its device
# layer view) and insertion (W1 30 m, CUDA, in a batch).
# Usage: bash scripts/layers_bench.sh BASELINE_SRC [STEP...]
#   BASELINE_SRC  a source tree of the baseline commit (e.g. `git archive COMMIT | tar -x -C DIR`,
#                 carried under .device/)
#   STEP          build | workloads | frontiers | collision | insert (default: all, in order)
# Builds go to build-old/ and build-device/ (this tree: scripts/device_check.sh's build), W1 to out/workloads, the map to out/w1.fgm (kept
# on a warm machine between calls); logs to $OUT (or out/layers).
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
old_src="$(cd "${1:?usage: layers_bench.sh BASELINE_SRC [STEP...]}" && pwd)"
shift
steps=("$@")
[ ${#steps[@]} -eq 0 ] && steps=(build workloads frontiers collision insert)
out="${OUT:-$root/out/layers}"
# LAYERS_TREES="old device" (default) or one of them: which builds the steps run.
read -r -a trees <<<"${LAYERS_TREES:-old device}"
mkdir -p "$out" "$root/out"
targets=(fragg_map_bench fragg_map_frontier_bench fragg_map_collision_bench)
status=0

build_tree() {  # SRC BUILD_DIR LOG
  cmake -S "$1" -B "$2" -DFRAGG_WITH_ROS=OFF -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CUDA_ARCHITECTURES=90 >"$3" 2>&1 &&
    cmake --build "$2" -j "$(nproc)" --target "${targets[@]}" >>"$3" 2>&1
}

for step in "${steps[@]}"; do
  case "$step" in
    build)
      # This tree as scripts/device_check.sh builds it (every target, the gpu tests too); of the
      # baseline the three benchmarks (the workload and the map come from this tree's tools).
      build_tree "$old_src" "$root/build-old" "$out/build_old.log" &
      OUT="$out" bash "$root/scripts/device_check.sh" || status=1
      wait || { echo "baseline build failed"; grep -m5 error "$out/build_old.log"; status=1; }
      echo "builds done" ;;
    workloads)
      [ -d "$root/out/workloads/w1_lidar360" ] ||
        bash "$root/scripts/make_workloads.sh" --out "$root/out/workloads" --only w1 \
          --sim "$root/build-device/bin/fragg_map_sim" 2>&1 | grep -v "^  " | tail -3
      [ -f "$root/out/w1.fgm" ] ||
        "$root/build-device/bin/fragg_map" build "$root/out/workloads/w1_lidar360" \
          -o "$root/out/w1.fgm" --resolution 0.05 --max-range 30 --backend cuda \
          >"$out/w1_build.log" 2>&1 || { tail -3 "$out/w1_build.log"; status=1; } ;;
    frontiers)
      for tree in "${trees[@]}"; do
        for backend in cuda cpu; do
          "$root/build-$tree/bin/fragg_map_frontier_bench" --workloads "$root/out/workloads" \
            --backend "$backend" --json "$out/frontiers_${tree}_$backend.json" \
            >"$out/frontiers_${tree}_$backend.log" 2>&1 || status=1
          echo "== frontiers $tree $backend"
          grep -iE "incremental|full|gain|clusters" "$out/frontiers_${tree}_$backend.log" | head -8
        done
      done ;;
    collision)
      for tree in "${trees[@]}"; do
        "$root/build-$tree/bin/fragg_map_collision_bench" --map "$root/out/w1.fgm" \
          --backends cpu cuda --fcl-poses 0 --json "$out/collision_$tree.json" \
          >"$out/collision_$tree.log" 2>&1 || status=1
        echo "== collision $tree"
        grep -E "box|mesh|differ" "$out/collision_$tree.log" | head -12
      done ;;
    insert)
      for tree in "${trees[@]}"; do
        "$root/build-$tree/bin/fragg_map_bench" --no-real --synthetic-scans 0 --workloads \
          "$root/out/workloads" --only W1 --backends cuda cuda+sequence --octomap-scans 0 \
          --repeats 2 >"$out/insert_$tree.log" 2>&1 || status=1
        echo "== insert $tree"
        grep -E "^\| W1|p99 without" "$out/insert_$tree.log"
      done ;;
    *) echo "unknown step $step"; exit 2 ;;
  esac
done
exit $status
