#!/usr/bin/env bash
# Issue 35's open GPU figures side by side in device calls (each call at most 10 minutes): the
# node (scripts/device_node_rate.sh, W1 5 cm, 620 clouds, every output subscribed at 1 Hz) and
# the outputs' harness, one build, settings alternated in the same call. Steps, in the order to
# run them (one or more a call; `record` first on a fresh machine: it records the ~2 GB bag):
#   record    one node run at 10 clouds/s (records the bag; its figures count too)
#   shares    shares_between_clouds:=true / :=false, alternated, --rounds times
#   hugetlb   the launch environment as it is / without GLIBC_TUNABLES (malloc on 4 KiB pages)
#   rates     20 clouds/s (620) and 262,144-point clouds at 10/s (300)
#   harness   fragg_map_server_overhead --backend cuda: --sync-between --shares-between /
#             --sync-between, 100 clouds
# Usage (on the device, in the checkout, .device/ros.tar.xz carried):
#   bash scripts/device_issue35.sh [--rounds N] [--backend B] [--clouds N] [name:=value ...] STEP...
# (--backend, --clouds and name:=value go to every node run: `--backend cpu --clouds 20` is a
# smoke check on a machine without a GPU; the harness step needs a CUDA build.)
# Logs and traces under $OUT (or out/issue35); the summaries on stdout.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${OUT:-$root/out/issue35}"
rounds=1
steps=()
extra_args=()
clouds=620
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) rounds="${2:?--rounds needs a number}"; shift 2 ;;
    --backend) extra_args+=(--backend "${2:?--backend needs a name}"); shift 2 ;;
    --clouds) clouds="${2:?--clouds needs a number}"; shift 2 ;;
    *:=*) extra_args+=("$1"); shift ;;
    record | shares | hugetlb | rates | harness) steps+=("$1"); shift ;;
    *) echo "device_issue35: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[ ${#steps[@]} -gt 0 ] || { echo "usage: bash scripts/device_issue35.sh [--rounds N] STEP..." >&2; exit 2; }
mkdir -p "$out"
status=0
run=0

# One node run: LABEL, then device_node_rate.sh's arguments; its summary lines on stdout.
node() {
  local label="$1"
  shift
  run=$((run + 1))
  local dir="$out/run${run}_$label"
  echo "== node $label: $*"
  bash "$root/scripts/device_node_rate.sh" --out "$dir" "$@" "${extra_args[@]+"${extra_args[@]}"}" \
    >"$dir.log" 2>&1 || status=1
  grep -E "inserted|receive-to-published|p99 by stage|p99 of the parts|over 20 ms|environment" \
    "$dir.log" | head -12
}

common=(--rate 10 --clouds "$clouds" marker_rate:=1 map_rate:=1)
for step in "${steps[@]}"; do
  case "$step" in
    record) node record "${common[@]}" ;;
    shares)
      for ((r = 0; r < rounds; ++r)); do
        node shares_true "${common[@]}" shares_between_clouds:=true
        node shares_false "${common[@]}" shares_between_clouds:=false
      done ;;
    hugetlb)
      for ((r = 0; r < rounds; ++r)); do
        node env_launch "${common[@]}"
        GLIBC_TUNABLES= node env_4k "${common[@]}"
      done ;;
    rates)
      node rate20 --rate 20 --clouds "$clouds" marker_rate:=1 map_rate:=1
      node points262k --rate 10 --clouds $((clouds / 2)) --azimuth-steps 2048 marker_rate:=1 \
        map_rate:=1 ;;
    harness)
      if [ ! -f "$root/.device/ros/env.sh" ]; then
        echo "device_issue35: no .device/ros (run a node step first: it unpacks the runtime)"
        status=1
        continue
      fi
      (
        # shellcheck disable=SC1091
        source "$root/.device/ros/env.sh"
        wl="$out/workloads"
        [ -d "$wl/w1_lidar360" ] || bash "$root/scripts/make_workloads.sh" --out "$wl" --only w1 \
          --sim "$(command -v fragg_map_sim)" >"$out/workloads.log" 2>&1
        for ((r = 0; r < rounds; ++r)); do
          for extra in "--sync-between --shares-between" "--sync-between"; do
            log="$out/harness_${r}_${extra// /}.log"
            echo "== harness: $extra"
            # shellcheck disable=SC2086
            GLIBC_TUNABLES=glibc.malloc.hugetlb=1 OMP_WAIT_POLICY=passive \
              fragg_map_server_overhead --workloads "$wl" --scans 100 --show 100 \
              --cloud-rate 10 --map-rate 1 --marker-rate 1 --after-only --backend cuda \
              --worst 12 $extra >"$log" 2>&1 || echo "harness failed: $log"
            grep -E "^after|between clouds" "$log"
          done
        done
      ) || status=1 ;;
  esac
done
exit $status
