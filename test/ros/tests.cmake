# fragg_map_ros: converters and parameters, plain gtests (no roscore needed).
if(FRAGG_HAVE_ROS)
  fragg_add_test(ros_cloud_from_msg_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/cloud_from_msg_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  fragg_add_test(ros_map_to_msgs_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/block_markers_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/marker_chunks_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/marker_wire_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/map_msgs_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/speckles_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/output_cache_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/mask_mirror_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/layer_masks_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/cell_colors_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/height_band_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  if(TARGET fragg_map_octomap)
    # projected_map on octomap_server's grid, against liboctomap's arithmetic.
    fragg_add_test(ros_octomap_grid_bounds_test
      SOURCES ${CMAKE_CURRENT_LIST_DIR}/octomap_grid_bounds_test.cpp
      LIBS fragg_map_ros fragg_map_octomap
      LABELS ros octomap)
  endif()
  fragg_add_test(ros_ground_filter_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/ground_filter_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  fragg_add_test(ros_server_params_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/server_params_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/reconfigure_params_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  fragg_add_test(ros_server_parts_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/server_parts_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  fragg_add_test(ros_collision_msgs_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/collision_msgs_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  fragg_add_test(ros_frontier_markers_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/frontier_markers_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  fragg_add_test(ros_pose_correction_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/pose_correction_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  # The frontier topics' mirror of the observed cells, copied a piece per read lock.
  fragg_add_test(ros_observed_mirror_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/observed_mirror_test.cpp
    LIBS fragg_map_nodelet
    LABELS ros)
  # The server's map files (.fgm, .bt): the nodelet library's loader.
  if(TARGET fragg_map_octomap)
    fragg_add_test(ros_map_file_loader_test
      SOURCES ${CMAKE_CURRENT_LIST_DIR}/map_file_loader_test.cpp
      LIBS fragg_map_nodelet fragg_map_octomap
      LABELS ros)
    # Corrupt and foreign map files; saves that run out of space (a 64 KiB tmpfs when root may
    # mount, else skipped with the reason; a file size limit always).
    fragg_add_test(ros_map_file_faults_test
      SOURCES ${CMAKE_CURRENT_LIST_DIR}/map_file_faults_test.cpp
      LIBS fragg_map_nodelet fragg_map_octomap
      LABELS ros)
  endif()
  # autosave/* and file_root, the Autosaver and loading an autosave (no master needed).
  fragg_add_test(ros_autosave_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/autosave_test.cpp
    LIBS fragg_map_nodelet fragg_map_ros
    LABELS ros)
  # The input path's faults (cloud_inserter): malformed clouds, huge points, bad transforms,
  # tf missing / from the future / too old, a cloud the map refuses; the map unchanged.
  fragg_add_test(ros_cloud_faults_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/cloud_faults_test.cpp
    LIBS fragg_map_nodelet
    LABELS ros)
  # Every cloud received in exactly one ~stats count (cloud_pipeline.h): queue drops, faults,
  # tf missing / too old (also after a wait in the queue), counters restarted mid-flight.
  fragg_add_test(ros_cloud_counts_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/cloud_counts_test.cpp
    LIBS fragg_map_nodelet
    LABELS ros)
  # file_root: the folder the server's file services are confined to (paths, .., symlinks).
  fragg_add_test(ros_file_root_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/file_root_test.cpp
    LIBS fragg_map_nodelet fragg_map_ros
    LABELS ros)
  # paging/* and the server's map on a page store (needs the page stores).
  if(TARGET fragg_map_store)
    fragg_add_test(ros_paging_params_test
      SOURCES ${CMAKE_CURRENT_LIST_DIR}/paging_params_test.cpp
      LIBS fragg_map_ros
      LABELS ros paging)
  endif()
  target_compile_definitions(ros_server_params_test PRIVATE
    FRAGG_PYTHON3="/usr/bin/python3"
    FRAGG_YAML_TO_XMLRPC="${CMAKE_CURRENT_LIST_DIR}/yaml_to_xmlrpc.py"
    FRAGG_CONFIG_DIR="${PROJECT_SOURCE_DIR}/config")
endif()

# rostests of the map server (the nodelet) on recorded bags: the smoke bag (with the service,
# malformed-cloud and missing-tf tests; the loop-closure correction test; the collision, truncate
# and merge services; the frontier service and topics), the real Velodyne pair (make_test_bag.py: float32
# unorganised + float64 organised with NaN, a leading-slash frame, one cloud without tf) and the
# real RGB-D frames (make_rgbd_bag.py: organised xyz+rgb depth clouds in an optical frame).
if(FRAGG_HAVE_ROS AND FRAGG_SMOKE_BAG)
  find_package(rostest REQUIRED)
  # (add_rostest puts the ARGS into target and file names: keep them short.)
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_smoke.test
    ARGS bag:=${FRAGG_SMOKE_BAG})
  # Loop-closure correction (~correct_poses, corrected_path) on the same bag.
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_correction.test
    ARGS bag:=${FRAGG_SMOKE_BAG})
  # ~check_collision against `fragg_map collide`, ~truncate + ~merge back to the same map.
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_services.test
    ARGS bag:=${FRAGG_SMOKE_BAG})
  # SIGKILL under load, restart, at most one save cycle lost, the map continues, SIGINT saves
  # (waits on the node's progress). Each start of the node reads topics of its own, so that
  # no publisher is re-created on a topic (that likely raced in roscpp: 1 run in 6 never
  # connected).
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_autosave.test
    ARGS bag:=${FRAGG_SMOKE_BAG})
  # The short soak (scripts/soak.sh: ~2 minutes; the 30-minute run is in docs/reliability.md).
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_soak.test
    ARGS bag:=${FRAGG_SMOKE_BAG})
  # ~get_frontiers against `fragg_map frontiers` on the saved map; the frontier topics only
  # while subscribed, incremental after an insertion.
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_frontiers.test
    ARGS bag:=${FRAGG_SMOKE_BAG})
  # Issue 35's Done-when: the smoke bag at 2 clouds/s, every output subscribed: 0 drops, every
  # cloud in one count, latency and trace_csv, incremental markers equal to a full rebuild.
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_rate.test
    ARGS bag:=${FRAGG_SMOKE_BAG})
  if(EXISTS ${FRAGG_REAL_DATA}/small_gicp_pair/target.ply)
    set(_fragg_velodyne_bag ${CMAKE_BINARY_DIR}/bags/velodyne.bag)
    add_custom_command(OUTPUT ${_fragg_velodyne_bag}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${CMAKE_BINARY_DIR}/bags
      COMMAND /usr/bin/python3 ${CMAKE_CURRENT_LIST_DIR}/../io/make_test_bag.py
              ${_fragg_velodyne_bag} ${FRAGG_REAL_DATA}/small_gicp_pair
      DEPENDS ${CMAKE_CURRENT_LIST_DIR}/../io/make_test_bag.py
      COMMENT "rostest bag: real Velodyne pair"
      VERBATIM)
    add_custom_target(fragg_map_rostest_bags ALL DEPENDS ${_fragg_velodyne_bag})
    # With OctoMap's map of the bag: >= 99.998 % of the cells either map knows agree (measured:
    # 33 of 4,048,248 differ, 99.9992 %). The topic comes first in ARGS: add_rostest names the
    # result file after the ARGS up to the first '.', and scripts/test.sh requires this result
    # by that name.
    add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_bag.test
      ARGS topic:=/velodyne_points bag:=${_fragg_velodyne_bag} scans:=2 no_tf:=1
           octomap:=0.99998 name:=map_server_bag_velodyne)
  endif()
  # The real RGB-D frames as organised depth clouds (make_rgbd_bag.py: 49 MB, made at build
  # time, never committed).
  set(_fragg_rgbd_data ${FRAGG_REAL_DATA}/slambook2_ch5_rgbd)
  if(EXISTS ${_fragg_rgbd_data}/pose.txt)
    set(_fragg_rgbd_bag ${CMAKE_BINARY_DIR}/bags/rgbd.bag)
    add_custom_command(OUTPUT ${_fragg_rgbd_bag}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${CMAKE_BINARY_DIR}/bags
      COMMAND /usr/bin/python3 ${CMAKE_CURRENT_LIST_DIR}/../rostest/make_rgbd_bag.py
              ${_fragg_rgbd_bag} ${_fragg_rgbd_data}
      DEPENDS ${CMAKE_CURRENT_LIST_DIR}/../rostest/make_rgbd_bag.py
      COMMENT "rostest bag: real RGB-D frames as organised depth clouds"
      VERBATIM)
    add_custom_target(fragg_map_rostest_rgbd_bag ALL DEPENDS ${_fragg_rgbd_bag})
    add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_rgbd.test
      ARGS bag:=${_fragg_rgbd_bag} data:=${_fragg_rgbd_data})
    # The same bag into the node with config/default.yaml (kept scans included), as a user
    # switching from octomap_server runs it: its map against OctoMap's map of the bag,
    # >= 99.99 % of the cells either knows (measured: 2 of 436,222 differ).
    if(octomap_FOUND)
      add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_bag.test
        ARGS topic:=/camera/depth_registered/points bag:=${_fragg_rgbd_bag} scans:=5
             rate:=0.5 octomap:=0.9999 name:=map_server_bag_rgbd)
    endif()
  endif()
else()
  # Without ROS: the server's ROS-free parts (cloud queue, marker throttle, timing statistics)
  # still run, e.g. in the TSan build of scripts/sanitize.sh.
  fragg_add_test(ros_server_parts_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/server_parts_test.cpp
            ${PROJECT_SOURCE_DIR}/src/ros/timing_stats.cpp
    LABELS core)
  target_include_directories(ros_server_parts_test PRIVATE ${PROJECT_SOURCE_DIR}/include)
endif()
