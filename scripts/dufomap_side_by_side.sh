#!/usr/bin/env bash
# DUFOMap beside fragg_map and OctoMap on W5 and W6 (issue 37, item 4), after
# scripts/make_workloads.sh (w5, w6) and, for the shared-ghost rows, scripts/eval_dynamic.sh:
#  1. builds DUFOMap's ufomap library (KTH-RPL/dufomap at d3df8fc, the last commit that carried
#     ufomap in its own tree) and scripts/dufomap/dufomap_eval.cpp against it (C++20, TBB, lz4,
#     lzf: apt-get install libtbb-dev liblz4-dev liblzf-dev), and scripts/dufomap/kth_io.cpp
#     against a plain CMake build of fragg_map (its libfragg_map_core.a), all under OUT/build;
#  2. converts each workload's scans with kth_io convert (fragg's own dataset reader: the same
#     finite points, the same ground-truth poses as fragg_map build and eval) into the KTH
#     DynamicMap benchmark's PCD format, runs DUFOMap over them with its config's parameters
#     (inflate_unknown 1, inflate_hits_dist 0.2 m) at fragg's resolution and max range, and
#     writes its static map (the cells of the points it keeps) as a .bt;
#  3. fragg_map eval MAP.bt --scene STATIC_TRUTH --labels DATASET --label-max-range R --json:
#     SA, DA and ghost cells as for fragg's and OctoMap's maps; DUFOMap's own point-level SA/DA
#     and its ms per scan (insertPointCloud alone, its TBB threads) beside them;
#  4. with --fragg DIR (an eval_dynamic.sh --out folder holding w5_on.fgm, w5_octomap.bt...):
#     the ghost cells DUFOMap shares with fragg's maps and OctoMap's (kth_io intersect).
# Usage: bash scripts/dufomap_side_by_side.sh [--workloads DIR] [--out DIR] [--bin DIR]
#          [--fragg-build DIR] [--dufomap-git DIR] [--fragg DIR] [--only w5|w6]
#   --dufomap-git  a git directory holding KTH-RPL/dufomap's history (default: cloned into OUT)
#   --fragg-build  a plain CMake build of fragg_map (default: build-core) for kth_io
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
workloads="${FRAGG_WORKLOADS:-$HOME/.cache/fragg_map/workloads}"
out="" bin="" fragg_build="$repo/build-core" dufomap_git="" fragg_maps="" only="w5,w6"
commit=d3df8fc
while [ $# -gt 0 ]; do
  case "$1" in
    --workloads) workloads="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --bin) bin="$2"; shift 2 ;;
    --fragg-build) fragg_build="$2"; shift 2 ;;
    --dufomap-git) dufomap_git="$2"; shift 2 ;;
    --fragg) fragg_maps="$2"; shift 2 ;;
    --only) only="$2"; shift 2 ;;
    -h|--help) sed -n '2,21p' "$0"; exit 0 ;;
    *) echo "dufomap_side_by_side: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
out="${out:-$repo/out/dufomap}"
if [ -z "$bin" ]; then
  if [ -x "${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map/fragg_map" ]; then bin="${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map"
  else bin="$repo/build-core/bin"; fi
fi
fm="$bin/fragg_map"
[ -x "$fm" ] || { echo "dufomap_side_by_side: no fragg_map in $bin (build first)" >&2; exit 1; }
core_lib="$fragg_build/src/libfragg_map_core.a"
[ -f "$core_lib" ] || { echo "dufomap_side_by_side: no $core_lib (a plain CMake build: --fragg-build)" >&2; exit 1; }
mkdir -p "$out/build"

# 1. DUFOMap's source at $commit (never committed here: OUT is git-ignored under out/).
src="$out/build/dufomap-$commit"
if [ ! -f "$src/CMakeLists.txt" ]; then
  if [ -z "$dufomap_git" ]; then
    dufomap_git="$out/build/dufomap.git"
    [ -d "$dufomap_git" ] || git clone --bare https://github.com/KTH-RPL/dufomap "$dufomap_git"
  fi
  mkdir -p "$src"
  git -C "$dufomap_git" archive "$commit" | tar -x -C "$src"
fi
wrap="$out/build/wrap"
mkdir -p "$wrap"
cat > "$wrap/CMakeLists.txt" <<EOF
cmake_minimum_required(VERSION 3.17)
project(dufomap_side_by_side CXX)
add_subdirectory("$src" dufomap)
add_executable(dufomap_eval "$repo/scripts/dufomap/dufomap_eval.cpp")
set_target_properties(dufomap_eval PROPERTIES CXX_STANDARD 20 CXX_STANDARD_REQUIRED YES)
target_link_libraries(dufomap_eval PRIVATE UFO::Map)
EOF
cmake -S "$wrap" -B "$out/build/cmake" -DCMAKE_BUILD_TYPE=Release > "$out/build/cmake.log"
cmake --build "$out/build/cmake" --target dufomap_eval -j "${FRAGG_JOBS:-1}" > "$out/build/make.log"
dufomap="$out/build/cmake/dufomap_eval"
kth="$out/build/kth_io"
if [ ! -x "$kth" ] || [ "$kth" -ot "$repo/scripts/dufomap/kth_io.cpp" ] || [ "$kth" -ot "$core_lib" ]; then
  g++ -O2 -std=c++17 -I"$repo/include" -I/usr/include/eigen3 "$repo/scripts/dufomap/kth_io.cpp" \
    -o "$kth" "$core_lib" -lfmt -loctomap -loctomath -lzstd -lz -lpng -fopenmp
fi

run() {  # name dataset static_obj resolution range
  local name="$1" data="$2" obj="$3" res="$4" range="$5"
  [ -d "$data/labels" ] || { echo "dufomap_side_by_side: $data has no labels/ (make_workloads.sh --only $name)" >&2; exit 1; }
  "$kth" convert "$data" "$out/$name" > "$out/${name}_convert.log"
  DUFO_LABELS="$data" "$dufomap" "$out/$name" "$res" "$range" "$out/${name}_kept.xyz" \
    > "$out/${name}_dufomap.json"
  "$kth" tobt "$out/${name}_kept.xyz" "$res" "$out/${name}_dufomap.bt" > "$out/${name}_tobt.log" 2>&1
  "$fm" eval "$out/${name}_dufomap.bt" --scene "$obj" --labels "$data" --label-max-range "$range" \
    --json > "$out/${name}_dufomap.eval.json"
  local shared=()
  if [ -n "$fragg_maps" ]; then
    for m in off on octomap; do
      local map="$fragg_maps/${name}_$m.fgm"
      [ "$m" = octomap ] && map="$fragg_maps/${name}_octomap.bt"
      [ -f "$map" ] || continue
      local bt="$map"
      if [ "$m" != octomap ]; then bt="$out/${name}_fragg_$m.bt"; "$fm" export "$map" -o "$bt" > /dev/null; fi
      "$kth" intersect "$bt" "$out/${name}_dufomap.bt" "$out/${name}_shared_$m.bt" > /dev/null 2>&1
      "$fm" eval "$out/${name}_shared_$m.bt" --scene "$obj" --labels "$data" \
        --label-max-range "$range" --json > "$out/${name}_shared_$m.eval.json"
      "$fm" eval "$bt" --scene "$obj" --labels "$data" --label-max-range "$range" --json \
        > "$out/${name}_own_$m.eval.json"
      shared+=("$m")
    done
  fi
  python3 - "$out" "$name" "${shared[@]}" <<'PY'
import json, sys
out, name, shared = sys.argv[1], sys.argv[2], sys.argv[3:]
lines = open(f"{out}/{name}_dufomap.json").read().splitlines()
point = json.loads(lines[0])["point_level"]
run = json.loads(lines[1])
d = json.load(open(f"{out}/{name}_dufomap.eval.json"))["map"]["dynamic"]
print(f"| {name} | SA % | DA % | ghost cells | occupied | ms/scan |")
print("|---|---|---|---|---|---|")
print(f"| DUFOMap (its static map's cells) | {100*d['sa']:.2f} | {100*d['da']:.2f} | "
      f"{d['ghost_cells']:,} | {d['occupied']:,} | {run['ms_per_scan']['median']:.1f} "
      f"({run['threads']} TBB threads) |")
print(f"| DUFOMap (its verdict per point) | {100*point['sa']:.2f} | {100*point['da']:.2f} | | | |")
for m in shared:
    own = json.load(open(f"{out}/{name}_own_{m}.eval.json"))["map"]["dynamic"]
    both = json.load(open(f"{out}/{name}_shared_{m}.eval.json"))["map"]["dynamic"]
    print(f"- {name}: ghost cells of {m}: {own['ghost_cells']:,}, of which DUFOMap's map also "
          f"holds {both['ghost_cells']:,}")
PY
}

for w in ${only//,/ }; do
  case "$w" in
    w5) run w5 "$workloads/w5_movers" "$workloads/scenes/campus_movers.obj" 0.1 30 ;;
    w6) run w6 "$workloads/w6_people" "$workloads/scenes/office_people.obj" 0.05 6 ;;
    *) echo "dufomap_side_by_side: unknown workload '$w'" >&2; exit 2 ;;
  esac
done
