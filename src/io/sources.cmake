# Dataset readers. FRAGG_IO_SOURCES are ROS-free and go into fragg_map_core;
# FRAGG_IO_ROS_SOURCES (the ROS bag reader) go into fragg_map_rosbag, built only with ROS.
set(FRAGG_IO_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/io_util.cpp
  ${CMAKE_CURRENT_LIST_DIR}/lzf.cpp
  ${CMAKE_CURRENT_LIST_DIR}/pcd_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ply_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/xyz_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/kitti_bin_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/point_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/pose_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/depth_image.cpp
  ${CMAKE_CURRENT_LIST_DIR}/file_list_source.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scan_graph_source.cpp
  ${CMAKE_CURRENT_LIST_DIR}/kitti_source.cpp
  ${CMAKE_CURRENT_LIST_DIR}/point_folder_source.cpp
  ${CMAKE_CURRENT_LIST_DIR}/depth_folder_source.cpp
  ${CMAKE_CURRENT_LIST_DIR}/dataset.cpp
)
set(FRAGG_IO_ROS_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/rosbag_source.cpp
)
