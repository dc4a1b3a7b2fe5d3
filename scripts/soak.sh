#!/usr/bin/env bash
# Soak of the map server (issue 18): the nodelet fed the smoke bag's clouds looped at 10 Hz for
# a set time, with service calls interleaved (save, load, clear box, correct poses, truncate,
# merge, frontiers, collision, reset), a marker subscriber and an autosave every 5 s; samples
# its resident memory every 2 s and checks, at the end (scripts/soak.py does the driving):
#   - RSS bounded: after the warm-up (20% of the run, >= 20 s) the median of the last third of
#     the samples is at most --rss-ratio (1.1) x the median of the first third (medians: the
#     peaks are transient copies of the map, caught at random by the 2 s sampling; 0 leaves
#     this check out, for runs too short for thirds to hold maps of the same size);
#   - RSS with an empty map bounded: the RSS just after a ~reset_map of the final phase (heap
#     trimmed, queue drained; up to 3 resets 6 s apart, the lowest counts: an autosave's copy
#     of the map being written is in one reading only) is at most 1.25 x the lowest after a mix
#     reset + 64 MiB (anything the node keeps across resets shows there, the map's size not);
#   - clouds dropped by the queue policy only (~get_stats: dropped_no_tf = rejected = 0; a
#     cloud that waited in the queue longer than the tf buffer, dropped_tf_too_old, counts as
#     dropped by the queue);
#   - no service call failed, markers were received, no ERROR / FATAL line in the node's log;
#   - the final map equals `fragg_map build` on the bag: a final phase with no map-changing
#     service (~reset_map, the bag's clouds once, each sent when the previous one is inserted,
#     ~save_map), compared only when the stats say none of its clouds was dropped.
# Writes to --out: node.log, rss.tsv, map.tsv, resets.tsv, calls.tsv, summary.json and
# soak_rss.png (gnuplot).
# Usage: bash scripts/soak.sh [--minutes N | --seconds S] [--out DIR] [--bag BAG]
#          [--rss-ratio R] [--use-master] [common options: --ws DIR ...]
#   --use-master: use the running ROS master of ROS_MASTER_URI (a rostest's) instead of
#                 starting one on a free loopback port.
# The workspace must be built (scripts/build.sh; this script builds nothing).
set -euo pipefail
caller_master="${ROS_MASTER_URI:-}"  # common.sh sets its own; --use-master needs the caller's
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

seconds=600
out="$FRAGG_REPO/out/soak"
bag=""
use_master=0
rss_ratio=1.1
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --minutes) seconds=$(( ${2:?--minutes needs a number} * 60 )); shift 2 ;;
    --seconds) seconds="${2:?--seconds needs a number}"; shift 2 ;;
    --out) out="${2:?--out needs a folder}"; shift 2 ;;
    --bag) bag="${2:?--bag needs a file}"; shift 2 ;;
    --rss-ratio) rss_ratio="${2:?--rss-ratio needs a number}"; shift 2 ;;
    --use-master) use_master=1; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
fragg_usage() {
  echo "usage: bash scripts/soak.sh [--minutes N | --seconds S] [--out DIR] [--bag BAG]" \
    "[--rss-ratio R] [--use-master]"
  fragg_usage_common
}
fragg_parse_common "${args[@]+"${args[@]}"}"
[ -n "$bag" ] || bag="$FRAGG_WS/build/workloads/smoke.bag"
[ -f "$bag" ] || { echo "soak: no bag at $bag (build the workspace, or --bag)" >&2; exit 2; }
fragg="$FRAGG_WS/devel/lib/fragg_map/fragg_map"
[ -f "$FRAGG_WS/devel/lib/libfragg_map_nodelet.so" ] ||
  { echo "soak: no map server in $FRAGG_WS (build the workspace)" >&2; exit 2; }
# (fragg_map itself is needed at the end only, for the final comparison.)
[ -x "$fragg" ] || echo "soak: $fragg is not built yet; the final comparison needs it" >&2
mkdir -p "$out"
out="$(cd "$out" && pwd -P)"
rm -f "$out"/*.fgm "$out"/*.fgm.tmp.* "$out/summary.json"

set +u
# shellcheck disable=SC1091
source "$FRAGG_WS/devel/setup.bash"
set -u
export ROSCONSOLE_STDOUT_LINE_BUFFERED=1

master_pid="" node_pid=""
stop() {
  if [ -n "$node_pid" ] && kill -0 "$node_pid" 2>/dev/null; then
    kill -INT "$node_pid" 2>/dev/null || true
    for _ in $(seq 100); do kill -0 "$node_pid" 2>/dev/null || break; sleep 0.2; done
    kill -KILL "$node_pid" 2>/dev/null || true
  fi
  if [ -n "$master_pid" ] && kill -0 "$master_pid" 2>/dev/null; then
    kill -TERM "$master_pid" 2>/dev/null || true
    wait "$master_pid" 2>/dev/null || true
  fi
}
trap stop EXIT

if [ "$use_master" -eq 0 ]; then
  port="$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
  export ROS_MASTER_URI="http://127.0.0.1:$port" ROS_IP=127.0.0.1
  rosmaster --core -p "$port" >"$out/master.log" 2>&1 &
  master_pid=$!
  host=127.0.0.1
else
  [ -n "$caller_master" ] || { echo "soak: --use-master without ROS_MASTER_URI" >&2; exit 2; }
  export ROS_MASTER_URI="$caller_master"  # a rostest's master is on a port of its own
  hostport="${caller_master#*://}"
  hostport="${hostport%%/*}"
  host="${hostport%:*}"
  port="${hostport##*:}"
fi
# The master must answer (a wrong one would leave every ROS client waiting for ever).
for _ in $(seq 150); do (exec 3<>"/dev/tcp/$host/$port") 2>/dev/null && break; sleep 0.2; done
(exec 3<>"/dev/tcp/$host/$port") 2>/dev/null ||
  { echo "soak: no ROS master answers at $ROS_MASTER_URI" >&2; exit 2; }

fragg_step "map server soak: $seconds s on $bag (master $ROS_MASTER_URI, output $out)"
# The node's parameters: the default config (queue of 5 clouds), the CPU backend, a 16 MiB
# budget for the kept scans (the oldest points dropped beyond it, so that memory reaches its
# plateau early), markers throttled to 2 Hz, an autosave every 5 s into --out (file_root).
# Private parameters on the command line (no rosparam process per value: each takes seconds on
# a loaded machine); every other parameter keeps the node's default (config/default.yaml).
nodelet_bin=/usr/lib/nodelet/nodelet
[ -x "$nodelet_bin" ] || nodelet_bin="$(catkin_find --first-only nodelet nodelet)"
"$nodelet_bin" standalone fragg_map/MapServerNodelet __name:=fragg_map cloud_in:=/points \
  _backend:=cpu _frame_id:=map _scan_store/max_mb:=16 _marker_rate:=2.0 _file_root:="$out" \
  _autosave/path:=soak_autosave.fgm _autosave/period_s:=5.0 >"$out/node.log" 2>&1 &
node_pid=$!
echo "node pid $node_pid, log $out/node.log"

rc=0
/usr/bin/python3 "$FRAGG_REPO/scripts/soak.py" --bag "$bag" --topic /points --frame map \
  --pid "$node_pid" --cli "$fragg" --out "$out" --seconds "$seconds" --rss_ratio "$rss_ratio" ||
  rc=$?
stop
node_pid=""

fragg_step "node log"
errors="$(grep -E '\[ *(ERROR|FATAL)\]' "$out/node.log" || true)"
if [ -n "$errors" ]; then
  echo "soak: ERROR lines in the node's log:" >&2
  printf '%s\n' "$errors" | head -n 20 >&2
  rc=1
else
  echo "no ERROR or FATAL line in $out/node.log ($(wc -l <"$out/node.log") lines)"
fi
grep -E 'autosave' "$out/node.log" | head -n 5 || true

if command -v gnuplot >/dev/null && [ -s "$out/rss.tsv" ]; then
  gnuplot <<EOT
set terminal pngcairo size 900,500 noenhanced
set output "$out/soak_rss.png"
set title "fragg_map node soak: resident memory ($(date -u +%Y-%m-%d), $seconds s)"
set xlabel "time [s]"
set ylabel "RSS [MiB]"
set yrange [0:*]
set grid
set key outside below
plot "$out/rss.tsv" using 1:2 with lines lw 2 title "VmRSS (every 2 s)", \
     "$out/map.tsv" using 1:2 with lines lw 1 title "the map's host memory (~stats)", \
     "$out/resets.tsv" using 1:3 with points pt 7 ps 0.8 title "just after a map reset (empty map, heap trimmed)"
EOT
  echo "RSS curve: $out/soak_rss.png"
fi
if [ "$rc" -ne 0 ]; then
  echo "soak: FAILED (see $out/summary.json, $out/node.log)" >&2
  exit 1
fi
echo "soak: all checks passed ($out/summary.json)"
