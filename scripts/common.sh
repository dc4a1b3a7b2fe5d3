# Shared by scripts/build.sh, test.sh and demo.sh (sourced, not run): the environment of
# ../shared/ROS.md, option parsing and the catkin workspace build.
# shellcheck shell=bash

FRAGG_REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"

# Debian's python3 first (catkin needs its catkin_pkg; /usr/local's python3 lacks it).
export PATH=/usr/local/cuda/bin:/usr/sbin:/usr/bin:/sbin:/bin
# Loopback-only ROS networking, line-buffered ROS logs (rostests, later).
export ROS_MASTER_URI=http://127.0.0.1:11311 ROS_IP=127.0.0.1 ROSCONSOLE_STDOUT_LINE_BUFFERED=1

# The catkin workspace lies beside the checkout, never inside it: a workspace inside the package
# with its link back makes rospack and roslaunch walk a loop ("multiple files named
# [fragg_map.launch]"). Default: <checkout>_ws next to it (e.g. ~/fragg_map -> ~/fragg_map_ws).
fragg_default_ws() { printf '%s_ws\n' "$FRAGG_REPO"; }
FRAGG_WS="${FRAGG_WS:-$(fragg_default_ws)}"
FRAGG_JOBS="${FRAGG_JOBS:-2}"
# CUDA kernels: "all" (every supported architecture: build.sh, test.sh), "check" (CI, .ci/run:
# one architecture, the oldest supported, sm_75: every kernel compiled and checked by ptxas once,
# not seven times; a GPU-less CI machine runs none of them) or "machine" (the demo scripts: only
# the GPU present, native, and no CUDA at all without a GPU), or an architecture's number
# (90: sm_90 only, for another machine's GPU, e.g. the node staged by scripts/stage_ros.sh).
FRAGG_CUDA="${FRAGG_CUDA:-all}"
# The tests (FRAGG_BUILD_TESTS): ON for build.sh, test.sh and CI; OFF for the demo scripts, whose
# first run builds only what it runs. Passed on every catkin_make, so a workspace the demo
# configured builds its tests again under build.sh.
FRAGG_TESTS="${FRAGG_TESTS:-ON}"
# Unity builds of src/ (FRAGG_UNITY_BUILD: .cpp files compiled in batches): ON for the demo
# scripts, whose first run is a fresh build; OFF by default (an incremental rebuild recompiles a
# whole batch). Passed on every catkin_make, like FRAGG_TESTS.
FRAGG_UNITY="${FRAGG_UNITY:-OFF}"
FRAGG_DEPS=1

fragg_usage_common() {
  cat <<EOF
  --ws DIR      catkin workspace, outside the checkout (default: $(fragg_default_ws);
                env FRAGG_WS)
  --jobs N      parallel compile jobs (default: 2; env FRAGG_JOBS)
  --no-deps     do not check or install the Debian packages (scripts/install_deps.sh)
EOF
}

# Parses the options every script takes; unknown ones are an error.
fragg_parse_common() {
  while [ $# -gt 0 ]; do
    case "$1" in
      --ws) FRAGG_WS="${2:?--ws needs a directory}"; shift 2 ;;
      --ws=*) FRAGG_WS="${1#--ws=}"; shift ;;
      --jobs|-j) FRAGG_JOBS="${2:?--jobs needs a number}"; shift 2 ;;
      --jobs=*) FRAGG_JOBS="${1#--jobs=}"; shift ;;
      --no-deps) FRAGG_DEPS=0; shift ;;
      -h|--help) fragg_usage; exit 0 ;;
      *) echo "$(basename "$0"): unknown argument '$1'" >&2; fragg_usage >&2; exit 2 ;;
    esac
  done
  case "$FRAGG_JOBS" in
    ''|*[!0-9]*|0) echo "$(basename "$0"): --jobs must be a positive integer" >&2; exit 2 ;;
  esac
  FRAGG_WS="$(realpath -m "$FRAGG_WS")"  # checked before anything is created
  case "$FRAGG_WS/" in
    "$FRAGG_REPO"/*)
      echo "$(basename "$0"): the workspace $FRAGG_WS lies inside the package $FRAGG_REPO;" \
        "rospack and roslaunch would find every file many times: use a --ws outside it" >&2
      exit 2 ;;
  esac
  mkdir -p "$FRAGG_WS"
  if [ -L "$FRAGG_REPO/ws/src/fragg_map" ]; then
    echo "$(basename "$0"): warning: $FRAGG_REPO/ws is an old workspace inside the package" \
      "(roslaunch fragg_map X.launch fails on its copies); remove it: rm -rf $FRAGG_REPO/ws" >&2
  fi
}

# A step's heading, with the time since the script started (where a first run spends it).
fragg_step() { printf '\n==== %s [%s] ====\n' "$*" "$(fragg_elapsed)"; }

# install_deps.sh's options: the demo scripts set (--demo), which leaves out the packages only
# the tests, the format check, the benchmarks and the docs need.
FRAGG_DEPS_ARGS=()
fragg_install_deps() {
  if [ "$FRAGG_DEPS" -eq 1 ]; then
    fragg_step "Debian packages"
    bash "$FRAGG_REPO/scripts/install_deps.sh" "${FRAGG_DEPS_ARGS[@]+"${FRAGG_DEPS_ARGS[@]}"}"
  fi
}

# Links the repository into $FRAGG_WS/src/fragg_map (once) and builds the workspace in
# Release with Debian's python3: the make targets given, or every target. Returns catkin_make's
# status.
fragg_build_ws() {
  fragg_step "catkin build in $FRAGG_WS (-j$FRAGG_JOBS)"
  mkdir -p "$FRAGG_WS/src"
  local link="$FRAGG_WS/src/fragg_map"
  if [ -L "$link" ]; then
    if [ "$(cd "$link" && pwd -P)" != "$FRAGG_REPO" ]; then
      echo "$link points to $(readlink "$link"), not to $FRAGG_REPO: use another --ws" >&2
      return 1
    fi
  elif [ -e "$link" ]; then
    echo "$link exists and is not a link to $FRAGG_REPO: use another --ws" >&2
    return 1
  else
    ln -s "$FRAGG_REPO" "$link"
  fi
  fragg_catkin_make "$@"
}

# What the demo scripts run (demo.sh, demo_ros.sh), and nothing else: the CLI, the simulator's
# smoke workload (fragg_map_sim and its bag), the nodelet and the messages and services that
# rosservice calls. With tests off, one configure.
FRAGG_DEMO_TARGETS=(fragg_map_cli fragg_map_smoke_workload fragg_map_nodelet
  fragg_map_generate_messages)
fragg_build_demo() {
  FRAGG_TESTS=OFF
  fragg_build_ws "${FRAGG_DEMO_TARGETS[@]}"
}

# The CMake arguments for FRAGG_CUDA (set once by fragg_cuda_choice).
FRAGG_CUDA_ARGS=()
FRAGG_CUDA_NOTE=""
fragg_cuda_choice() {
  [ -n "$FRAGG_CUDA_NOTE" ] && return 0
  case "$FRAGG_CUDA" in
    all)
      FRAGG_CUDA_ARGS=(-DFRAGG_WITH_CUDA=ON -DFRAGG_CUDA_NATIVE=OFF)
      FRAGG_CUDA_NOTE="CUDA: kernels for every supported architecture (when nvcc is found)" ;;
    check)
      FRAGG_CUDA_ARGS=(-DFRAGG_WITH_CUDA=ON -DFRAGG_CUDA_NATIVE=OFF -DCMAKE_CUDA_ARCHITECTURES=75-real)
      FRAGG_CUDA_NOTE="CUDA: kernels compiled for sm_75 only, a compile check (when nvcc is found)" ;;
    machine)
      local gpu=""
      if command -v nvidia-smi >/dev/null 2>&1; then
        gpu="$(nvidia-smi -L 2>/dev/null | head -n 1 || true)"
      fi
      if [ -n "$gpu" ]; then
        FRAGG_CUDA_ARGS=(-DFRAGG_WITH_CUDA=ON -DFRAGG_CUDA_NATIVE=ON)
        FRAGG_CUDA_NOTE="CUDA: kernels for this machine's GPU only (native): $gpu"
      else
        FRAGG_CUDA_ARGS=(-DFRAGG_WITH_CUDA=OFF -DFRAGG_CUDA_NATIVE=OFF)
        FRAGG_CUDA_NOTE="CUDA: no GPU found (nvidia-smi): building without CUDA, CPU backend only"
      fi ;;
    [1-9][0-9]|[1-9][0-9][0-9])
      FRAGG_CUDA_ARGS=(-DFRAGG_WITH_CUDA=ON -DFRAGG_CUDA_NATIVE=OFF
        -DCMAKE_CUDA_ARCHITECTURES="$FRAGG_CUDA-real")
      FRAGG_CUDA_NOTE="CUDA: kernels compiled for sm_$FRAGG_CUDA only (another machine's GPU)" ;;
    *) echo "FRAGG_CUDA must be all, check, machine or an architecture (90), not '$FRAGG_CUDA'" >&2
       return 2 ;;
  esac
  echo "$FRAGG_CUDA_NOTE"
}

# catkin_make in $FRAGG_WS with the job count and the CMake arguments every run must repeat
# (a --force-cmake reconfigure without them would fall back to catkin's defaults).
fragg_catkin_make() {
  fragg_cuda_choice
  (cd "$FRAGG_WS" && catkin_make -j"$FRAGG_JOBS" "$@" -DCMAKE_BUILD_TYPE=Release \
    -DFRAGG_BUILD_TESTS="$FRAGG_TESTS" -DFRAGG_UNITY_BUILD="$FRAGG_UNITY" \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 \
    -DPython3_EXECUTABLE=/usr/bin/python3 \
    "${FRAGG_CUDA_ARGS[@]}")
}

# build.sh, demo.sh, demo_ros.sh and CI (test.sh): without an installed octomap_msgs (Debian has
# none), builds the messages-only stand-in of test/octomap_msgs_standin (octomap_msgs' own
# definitions: the same md5sums) in a workspace of its own, <ws>/octomap_msgs_standin, and
# sources it, so that fragg_map is built with its octomap_msgs outputs (octomap_binary,
# octomap_full, GetOctomap) that octomap_msgs' clients can read.
fragg_octomap_msgs_standin() {
  local p
  for p in /usr ${CMAKE_PREFIX_PATH:+${CMAKE_PREFIX_PATH//:/ }}; do
    if [ -e "$p/share/octomap_msgs/cmake/octomap_msgsConfig.cmake" ] &&
      [[ "$p" != "$FRAGG_WS/octomap_msgs_standin/"* ]]; then
      echo "octomap_msgs found in $p: no stand-in needed"
      return 0
    fi
  done
  local under="$FRAGG_WS/octomap_msgs_standin"
  fragg_step "octomap_msgs stand-in (messages only) in $under"
  mkdir -p "$under/src"
  ln -sfn "$FRAGG_REPO/test/octomap_msgs_standin/octomap_msgs" "$under/src/octomap_msgs"
  (cd "$under" && catkin_make -j"$FRAGG_JOBS" -DCMAKE_BUILD_TYPE=Release \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3) || return 1
  set +u
  # shellcheck disable=SC1091
  source "$under/devel/setup.bash"
  set -u
}

# Seconds since the script started, as "1m23s".
fragg_elapsed() {
  local s=$SECONDS
  printf '%dm%02ds' $((s / 60)) $((s % 60))
}

# Processes a script started beside its node (a master, players, listeners):
# fragg_stop_started stops each (TERM, then KILL after 10 s); scripts trap it on EXIT.
FRAGG_STARTED=()
# Stops PID with signal SIG, waiting up to 10 s before KILL.
fragg_stop_pid() {
  local pid="$1" sig="$2"
  kill -0 "$pid" 2>/dev/null || return 0
  kill "-$sig" "$pid" 2>/dev/null || true
  for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.2; done
  kill -KILL "$pid" 2>/dev/null || true
}
fragg_stop_started() {
  for pid in "${FRAGG_STARTED[@]+"${FRAGG_STARTED[@]}"}"; do fragg_stop_pid "$pid" TERM; done
}

# A ROS master of the script's own on a free loopback port (ROS_MASTER_URI exported), its output
# appended to LOG, the workspace sourced; returns once it answers. Its pid goes to
# FRAGG_STARTED (a bare rosmaster ignores SIGINT: fragg_stop_started TERMs it).
fragg_start_master() {
  local log="$1" port
  port="$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
  export ROS_MASTER_URI="http://127.0.0.1:$port"
  set +u
  # shellcheck disable=SC1091
  source "$FRAGG_WS/devel/setup.bash"
  set -u
  rosmaster --core -p "$port" >>"$log" 2>&1 &
  FRAGG_STARTED+=("$!")
  for _ in $(seq 50); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done
}
