#!/usr/bin/env bash
# Generates the standard workloads (DESIGN section 9) with fragg_map_sim, deterministically
# (fixed seeds; config/workloads/*.args), into a cache folder outside git:
#   scenes/campus.obj scenes/pipes.obj   ground truth for `fragg_map eval`
#   w1_lidar360/     KITTI folder, 100 x 179,968-point scans (campus street)
#   w2_depth/        depth-image folder, 100 x 640x480 frames (pipe room)
#   w3_loopclosure/  KITTI folder + poses_odom.txt, and w3_loopclosure.bag (drifting tf,
#                    ground-truth pose and path) when fragg_map_sim has bag output (ROS build)
#   smoke/           KITTI folder and smoke.bag (< 2 MB; bag with ROS only)
#   w5_movers/       KITTI folder + labels/*.dyn (1 = return from a mover), 120 x 32k-point
#                    scans of the campus street among 24 movers (config/scenes/campus_movers.json),
#                    and scenes/campus_movers.obj, its static truth (movers left out)
#   w6_people/       depth-image folder + labels/*.dyn, 150 x 320x240 frames of an office with
#                    five people walking and a door (config/scenes/office_people.json), and
#                    scenes/office_people.obj (static truth)
#   movers_smoke/    W5's scene, 12 x 4k-point scans (< 1 MB), for tests
#   w4_long_drive/   only when asked for (--only w4; scripts/w4.sh): KITTI folder, 579 scans
#                    of a 1,156 m loop through the campus laid out four times (~1.5 GB), and
#                    scenes/campus_long.obj
#   MANIFEST.sha256  checksums of every file: a rerun must give the same file
# Uses the catkin build's fragg_map_sim (<checkout>_ws/, with bag output) when there is one, else builds
# the plain CMake one (build-core/, no ROS: no bags) first.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"

usage() {
  cat <<USAGE
usage: bash scripts/make_workloads.sh [--out DIR] [--only w1,w2,w3,smoke,w4,w5,w6,movers_smoke] [--sim PATH] [--jobs N]
  --out DIR    cache folder (default: \$FRAGG_WORKLOADS or ~/.cache/fragg_map/workloads)
  --only LIST  comma-separated subset of w1,w2,w3,smoke,w4,w5,w6,movers_smoke (default:
               w1,w2,w3,smoke,w5,w6,movers_smoke; W4, the 1.5 GB long drive, only when named)
  --sim PATH   fragg_map_sim to use (default: <checkout>_ws/devel/lib/fragg_map/fragg_map_sim, else
               build-core/bin/fragg_map_sim, built with plain CMake when missing)
  --jobs N     compile jobs when building (default 2)
USAGE
}

out="${FRAGG_WORKLOADS:-$HOME/.cache/fragg_map/workloads}"
only="w1,w2,w3,smoke,w5,w6,movers_smoke"
sim=""
jobs=2
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="${2:?--out needs a folder}"; shift 2 ;;
    --only) only="${2:?--only needs a list}"; shift 2 ;;
    --sim) sim="${2:?--sim needs a path}"; shift 2 ;;
    --jobs) jobs="${2:?--jobs needs a number}"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "make_workloads: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
for w in ${only//,/ }; do
  case "$w" in w1|w2|w3|smoke|w4|w5|w6|movers_smoke) ;; *) echo "make_workloads: unknown workload '$w'" >&2; exit 2 ;; esac
done

if [ -z "$sim" ]; then
  if [ -x "${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map/fragg_map_sim" ]; then
    sim="${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map/fragg_map_sim"
  else
    sim="$repo/build-core/bin/fragg_map_sim"
    if [ ! -x "$sim" ]; then
      echo "make_workloads: building fragg_map_sim (plain CMake, build-core/)"
      cmake -S "$repo" -B "$repo/build-core" -DFRAGG_WITH_ROS=OFF -DCMAKE_BUILD_TYPE=Release >/dev/null
      cmake --build "$repo/build-core" -j"$jobs" --target fragg_map_sim
    fi
  fi
fi
[ -x "$sim" ] || { echo "make_workloads: no fragg_map_sim at $sim" >&2; exit 1; }
bags=0
[ "$("$sim" info)" = "bag_output yes" ] && bags=1
echo "make_workloads: $sim (bag output: $([ $bags -eq 1 ] && echo yes || echo no)) -> $out"

mkdir -p "$out/scenes"
out="$(cd "$out" && pwd -P)"
cd "$repo"  # scene paths in the .args files are relative to the repository
"$sim" scene config/scenes/campus.json -o "$out/scenes/campus.obj"
"$sim" scene config/scenes/pipes.json -o "$out/scenes/pipes.obj"
# Static truths of the mover scenes (the scene command writes the static mesh only).
"$sim" scene config/scenes/campus_movers.json -o "$out/scenes/campus_movers.obj"
"$sim" scene config/scenes/office_people.json -o "$out/scenes/office_people.obj"
case ",$only," in *,w4,*)
  "$sim" scene config/scenes/campus_long.json -o "$out/scenes/campus_long.obj" ;;
esac

# The record arguments of a workload, without comments.
args_of() { grep -v '^[[:space:]]*#' "$repo/config/workloads/$1.args"; }

run() {  # name, output flags...
  local name="$1"; shift
  rm -rf "${out:?}/$name" "$out/$name.bag"
  local start=$SECONDS
  # shellcheck disable=SC2046
  "$sim" record $(args_of "$name") "$@"
  echo "make_workloads: $name in $((SECONDS - start)) s"
}

bag_flag() {  # name -> --bag FILE when bags can be written
  if [ $bags -eq 1 ]; then echo "--bag $out/$1.bag"; else
    echo "make_workloads: $1: no bag (fragg_map_sim built without ROS)" >&2; fi
}

for w in ${only//,/ }; do
  case "$w" in
    w1) run w1_lidar360 --kitti "$out/w1_lidar360" ;;
    w2) run w2_depth --depth-folder "$out/w2_depth" ;;
    # shellcheck disable=SC2046
    w3) run w3_loopclosure --kitti "$out/w3_loopclosure" $(bag_flag w3_loopclosure) ;;
    # shellcheck disable=SC2046
    smoke) run smoke --kitti "$out/smoke" --organised $(bag_flag smoke) ;;
    w4) run w4_long_drive --kitti "$out/w4_long_drive" ;;
    w5) run w5_movers --kitti "$out/w5_movers" ;;
    w6) run w6_people --depth-folder "$out/w6_people" ;;
    movers_smoke) run movers_smoke --kitti "$out/movers_smoke" ;;
  esac
done

# Checksums of the workloads (not of eval/, where scripts/eval_workloads.sh puts its maps).
(cd "$out" && find . -type f ! -name MANIFEST.sha256 ! -path './eval/*' | LC_ALL=C sort |
  xargs sha256sum) \
  > "$out/MANIFEST.sha256"
echo "make_workloads: done; checksums in $out/MANIFEST.sha256"
du -sh "$out"/* | sed 's/^/  /'
