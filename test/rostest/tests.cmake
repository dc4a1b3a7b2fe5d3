# rostests that need no recorded bag: roslaunch by package name, the node killed on a page store,
# service calls during long insertions and during a long query, map_rate on a cloud stream, and
# fragg_map as a drop-in for octomap_server (an octomap_server YAML through
# launch/octomap_compat.launch, every row of the compatibility table of docs/ros.md).
if(FRAGG_HAVE_ROS)
  find_package(rostest REQUIRED)
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/roslaunch_by_name.test)
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/octomap_compat.test)
  # kill -9 of the node on a page store, restarted on it (issue 13's durability in the node).
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/map_server_store_kill.test)
  # ~get_stats, ~save_map and ~clear_bbox called while big clouds are inserted (issue 18).
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/map_server_busy.test)
  # Issue 35, item 4: while a long ~get_frontiers runs, ~get_stats and ~save_map answer and
  # clouds are inserted (services on threads of their own, the query on a copy of the map).
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/map_server_side_by_side.test)
  # The server's insertion path (CloudInput: subscriber, queue, insertion thread) leaves the map
  # unlocked between every two clouds: a query from another thread gets in each time.
  add_rostest_gtest(cloud_input_lock_test ${CMAKE_CURRENT_LIST_DIR}/cloud_input_lock.test
    ${CMAKE_CURRENT_LIST_DIR}/../ros/cloud_input_lock_test.cpp)
  target_link_libraries(cloud_input_lock_test fragg_map_nodelet)
  target_include_directories(cloud_input_lock_test PRIVATE ${CMAKE_CURRENT_LIST_DIR}/../ros)
  fragg_target_flags(cloud_input_lock_test)
  # map_rate / marker_rate: the whole-map outputs and markers throttled on a 10 Hz stream, the
  # held-back clouds flushed by the timer, ~reset_map published at once.
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/map_server_map_rate.test)
endif()
