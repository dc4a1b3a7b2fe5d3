# fragg_map_ros (ROS builds only): stateless converters between ROS messages and the map, the
# ground filter (PCL plane segmentation), the server's parameters, collision shapes from
# requests and their markers.
set(FRAGG_ROS_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/cloud_from_msg.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ground_filter.cpp
  ${CMAKE_CURRENT_LIST_DIR}/height_color.cpp
  ${CMAKE_CURRENT_LIST_DIR}/block_markers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/marker_wire.cpp
  ${CMAKE_CURRENT_LIST_DIR}/publish_buffers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/wire_payload.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cell_colors.cpp
  ${CMAKE_CURRENT_LIST_DIR}/occupied_cloud.cpp
  ${CMAKE_CURRENT_LIST_DIR}/output_cache.cpp
  ${CMAKE_CURRENT_LIST_DIR}/speckles.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mask_mirror.cpp
  ${CMAKE_CURRENT_LIST_DIR}/projected_map.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frustum_marker.cpp
  ${CMAKE_CURRENT_LIST_DIR}/server_params.cpp
  ${CMAKE_CURRENT_LIST_DIR}/timing_stats.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scan_stamp_index.cpp
  ${CMAKE_CURRENT_LIST_DIR}/pose_correction.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collision_shape_msg.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collision_markers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frontier_markers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/paging_params.cpp
  ${CMAKE_CURRENT_LIST_DIR}/autosave_params.cpp
  ${CMAKE_CURRENT_LIST_DIR}/reconfigure_params.cpp
)
