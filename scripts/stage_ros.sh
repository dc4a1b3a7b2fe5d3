#!/usr/bin/env bash
# Stages what the map server needs to run on a machine without ROS (the GPU machine: Ubuntu
# 24.04, python3.12, no package registry) from this machine's Debian packages, into DEST
# (default .device/ros under the checkout), the way ../shared/tools/stage-octomap.sh stages
# liboctomap:
#   bin/      the node (fragg_map_server, which loads fragg_map/MapServerNodelet through
#             pluginlib), rosbag's C++ player and recorder, the master's script, fragg_map_sim,
#             fragg_map_server_overhead (the outputs' harness; `--backend cuda` there)
#   lib/      the nodelet library and every shared library these load (ldd), but the C/C++
#             runtime the other machine has newer (glibc, libstdc++, libgcc_s)
#   share/    package.xml of fragg_map and its dependencies, nodelet_plugins.xml (the package
#             index pluginlib reads through ROS_PACKAGE_PATH)
#   python/   the master (rosmaster, pure Python: rosgraph, defusedxml, and what they import),
#             run by the other machine's python3 (3.12; Debian's modules are 3.11 but pure)
#   env.sh    PATH, LD_LIBRARY_PATH, PYTHONPATH, ROS_PACKAGE_PATH, CMAKE_PREFIX_PATH,
#             ROS_MASTER_URI (loopback, port ROS_PORT or 11311) for a shell there
#   run_rate.sh  master + node + bag at a rate; the trace_csv rows by outcome at the end
#   (scripts/device_node_rate.sh: W1 at sensor rate with every output subscribed, on it)
# Checked on this machine (Debian 12) from a bare environment (env -i, only env.sh): the smoke
# bag played through the staged node, 10 of 10 clouds inserted. Not run on the GPU machine.
# The node must be built with CUDA for the GPU (nvcc is here: `FRAGG_CUDA=90 bash scripts/build.sh --ws WS`, sm_90 only) first;
# NODE names it (default: <checkout>_ws/devel/lib/fragg_map/fragg_map_server).
#   bash scripts/stage_ros.sh [DEST]
# On the GPU machine (run's carry: .device/ros.tar.xz; the folder is over 64 MiB):
#   tar -C .device -xJf .device/ros.tar.xz && source .device/ros/env.sh &&
#   OUT=$OUT bash .device/ros/run_rate.sh BAG RATE _backend:=cuda _resolution:=0.05
set -euo pipefail
top=$(git rev-parse --show-toplevel 2>/dev/null || pwd)
dest=${1:-$top/.device/ros}
node=${NODE:-${top}_ws/devel/lib/fragg_map/fragg_map_server}
# The nodelet library the node loads through pluginlib (not an ldd dependency of the node).
nodelet_lib=${NODELET_LIB:-$(dirname "$(dirname "$node")")/libfragg_map_nodelet.so}
[ -x "$node" ] || { echo "stage_ros: no node at $node (build it, or set NODE)" >&2; exit 2; }
[ -f "$nodelet_lib" ] || { echo "stage_ros: no $nodelet_lib (set NODELET_LIB)" >&2; exit 2; }
for exe in /usr/lib/rosbag/play /usr/lib/rosbag/record /usr/bin/rosmaster; do
  [ -e "$exe" ] || { echo "stage_ros: $exe missing (apt-get install rosbag ros-core)" >&2; exit 2; }
done
rm -rf "$dest" && mkdir -p "$dest/bin" "$dest/lib" "$dest/python"
cp -L "$node" "$dest/bin/fragg_map_server"
cp -L /usr/lib/rosbag/play /usr/lib/rosbag/record "$dest/bin/"
# The workspace's simulator (bag output), so that the GPU machine records W1 bags itself
# (scripts/device_node_rate.sh): a 600-cloud W1 bag is ~2 GB, too big to carry.
sim=${SIM:-$(dirname "$node")/fragg_map_sim}
if [ -x "$sim" ]; then cp -L "$sim" "$dest/bin/fragg_map_sim"; else
  echo "stage_ros: no $sim: device_node_rate.sh needs --bag then" >&2; fi
# The server overhead harness (issue 35's outputs-per-cloud goal "on both machines": it needs
# roscpp's serialisation and message headers, so it is not in the GPU machine's ROS-less build).
overhead=${OVERHEAD:-$(dirname "$node")/fragg_map_server_overhead}
if [ -x "$overhead" ]; then cp -L "$overhead" "$dest/bin/"; else
  echo "stage_ros: no $overhead: the overhead harness is not staged" >&2; fi
# Shared libraries: everything ldd resolves, but the runtime the newer machine brings.
skip='^(libc|libm|libdl|libpthread|librt|libresolv|ld-linux-x86-64|libstdc\+\+|libgcc_s)\.so'
for exe in "$dest"/bin/* "$nodelet_lib"; do
  ldd "$exe" | awk '/=> \//{print $3}'
  [ "$exe" = "$nodelet_lib" ] && echo "$nodelet_lib"
done | sort -u | while read -r lib; do
  base=$(basename "$lib")
  [[ "$base" =~ $skip ]] && continue
  cp -L "$lib" "$dest/lib/$base"
done
missing=$(for exe in "$dest"/bin/* "$dest/lib/libfragg_map_nodelet.so"; do
  LD_LIBRARY_PATH="$dest/lib" ldd "$exe" | grep "not found" || true
done)
[ -z "$missing" ] || { echo "stage_ros: unresolved libraries:" >&2; echo "$missing" >&2; exit 1; }
# The node loads fragg_map/MapServerNodelet through pluginlib: the package index (rospack
# crawls ROS_PACKAGE_PATH for package.xml files) and the plugin description; the library is
# looked up under CMAKE_PREFIX_PATH/lib (lib/ here).
mkdir -p "$dest/share/fragg_map"
cp "$top/package.xml" "$top/nodelet_plugins.xml" "$dest/share/fragg_map/"
for dep in $(grep -o '<[a-z_]*depend>[^<]*' "$top/package.xml" | sed 's/.*>//' | sort -u); do
  if [ -f "/usr/share/$dep/package.xml" ]; then
    mkdir -p "$dest/share/$dep"
    cp "/usr/share/$dep/package.xml" "$dest/share/$dep/"
    [ -f "/usr/share/$dep/nodelet_plugins.xml" ] || continue  # pcl_ros declares its own
  fi
done
# A bag writer (fragg_map_sim record, rosbag's recorder) loads rosbag_storage's default
# encryptor through pluginlib: its package index, plugin description and library (with the
# libraries it needs), which the ldd pass above does not see.
enc=$(find /usr/lib -name 'librosbag_default_encryption_plugins.so' 2>/dev/null | head -1)
if [ -f /usr/share/rosbag_storage/encryptor_plugins.xml ] && [ -n "$enc" ]; then
  mkdir -p "$dest/share/rosbag_storage"
  cp /usr/share/rosbag_storage/package.xml /usr/share/rosbag_storage/encryptor_plugins.xml \
    "$dest/share/rosbag_storage/"
  cp -L "$enc" "$dest/lib/"
  ldd "$enc" | awk '/=> \//{print $3}' | while read -r lib; do
    base=$(basename "$lib")
    [[ "$base" =~ $skip ]] || [ -e "$dest/lib/$base" ] || cp -L "$lib" "$dest/lib/$base"
  done
else
  echo "stage_ros: rosbag_storage's encryptor plugin not found: bags cannot be written there" >&2
fi
# The master: rosmaster and the pure-Python modules it imports (checked below by importing
# them from the staged folder alone).
py=/usr/lib/python3/dist-packages
for mod in rosmaster rosgraph defusedxml yaml rospkg catkin_pkg; do
  [ -e "$py/$mod" ] && cp -a "$py/$mod" "$dest/python/"
done
cp /usr/bin/rosmaster "$dest/bin/rosmaster"
sed -i '1s|.*|#!/usr/bin/env python3|' "$dest/bin/rosmaster"
env -i PATH=/usr/bin:/bin PYTHONPATH="$dest/python" /usr/bin/python3 -S -c \
  'import sys; sys.path.insert(0, sys.argv[1]); import rosmaster.main, rosgraph.xmlrpc' \
  "$dest/python" || { echo "stage_ros: the staged master does not import" >&2; exit 1; }
cat > "$dest/env.sh" <<'ENV'
# source .device/ros/env.sh (bash): the staged ROS runtime, loopback master.
_ros=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
export PATH="$_ros/bin:$PATH"
export LD_LIBRARY_PATH="$_ros/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export PYTHONPATH="$_ros/python${PYTHONPATH:+:$PYTHONPATH}"
export ROS_MASTER_URI=http://127.0.0.1:${ROS_PORT:-11311} ROS_IP=127.0.0.1 ROS_HOME="${ROS_HOME:-/tmp/ros_home}"
export ROSCONSOLE_STDOUT_LINE_BUFFERED=1
export ROS_PACKAGE_PATH="$_ros/share" CMAKE_PREFIX_PATH="$_ros${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
ENV
cat > "$dest/run_rate.sh" <<'RUN'
#!/usr/bin/env bash
# bash run_rate.sh BAG RATE [node params as _name:=value ...]: master, the node on /points
# (trace_csv to $OUT or /tmp), the bag played at RATE, then the node's counters and latency
# (~stats, latched) printed. Needs env.sh sourced.
set -euo pipefail
bag=$1; rate=$2; shift 2
out=${OUT:-/tmp}
port=${ROS_MASTER_URI##*:}
rosmaster --core -p "${port%/}" > "$out/master.log" 2>&1 & master=$!
node_pid=
trap 'kill ${node_pid:-} 2>/dev/null || true; kill $master 2>/dev/null || true' EXIT
sleep 3
fragg_map_server cloud_in:=/points _frame_id:=map _trace_csv:="$out/trace.csv" "$@" \
  > "$out/node.log" 2>&1 & node_pid=$!
sleep 3
play --clock -q -r "$rate" "$bag"
sleep 5   # the queue drains; then the last ~stats is in node.log's trace and trace.csv
kill -INT $node_pid; wait $node_pid || true
echo "rows by outcome:"; tail -n +2 "$out/trace.csv" | cut -d, -f3 | sort | uniq -c
RUN
chmod +x "$dest/run_rate.sh"
echo "staged the ROS runtime in $dest ($(du -sh "$dest" | cut -f1); lib $(du -sh "$dest/lib" | cut -f1))"
# The device run carries at most 64 MiB of ignored files: the folder also as one archive
# (there: tar -C .device -xJf .device/ros.tar.xz), carried instead of the folder. xz, not
# zstd: the GPU machine's Ubuntu has no zstd.
rm -f "$dest.tar.zst"
tar -C "$(dirname "$dest")" -I 'xz -6 -T0' -cf "$dest.tar.xz" "$(basename "$dest")"
echo "and as $dest.tar.xz ($(du -sh "$dest.tar.xz" | cut -f1))"
