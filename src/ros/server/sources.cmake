# The map server (ROS builds only): the nodelet library and the node that loads it.
set(FRAGG_ROS_SERVER_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/server_stats.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_publishers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_services.cpp
  ${CMAKE_CURRENT_LIST_DIR}/service_threads.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_copy.cpp
  ${CMAKE_CURRENT_LIST_DIR}/observed_mirror.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_file_loader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/autosave.cpp
  ${CMAKE_CURRENT_LIST_DIR}/file_root.cpp
  ${CMAKE_CURRENT_LIST_DIR}/process_memory.cpp
  ${CMAKE_CURRENT_LIST_DIR}/octomap_compat_services.cpp
  ${CMAKE_CURRENT_LIST_DIR}/octomap_compat_notes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/correction_service.cpp
  ${CMAKE_CURRENT_LIST_DIR}/submap_services.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collision_service.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frontier_service.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frontier_publisher.cpp
  ${CMAKE_CURRENT_LIST_DIR}/path_corrector.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cloud_inserter.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cloud_trace.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cloud_pipeline.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cloud_input.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_server.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_server_nodelet.cpp
)
# With octomap_msgs (and liboctomap) only: octomap_binary / octomap_full.
set(FRAGG_ROS_OCTOMAP_MSGS_SOURCES ${CMAKE_CURRENT_LIST_DIR}/octomap_outputs.cpp)
set(FRAGG_ROS_SERVER_NODE_SOURCES ${CMAKE_CURRENT_LIST_DIR}/server_node.cpp)
# With dynamic_reconfigure only: ~set_parameters (cfg/MapServer.cfg).
set(FRAGG_ROS_RECONFIGURE_SOURCES ${CMAKE_CURRENT_LIST_DIR}/reconfigure.cpp)
