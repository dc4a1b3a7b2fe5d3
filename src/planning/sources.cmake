# ROS-free planning queries over a map (fragg_map_planning): collision checks of boxes, spheres,
# capsules and triangle meshes (single poses, OpenMP or CUDA batches, paths), waypoint files;
# frontier cells (full and incremental), clusters, viewpoints and information gain.
set(FRAGG_PLANNING_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/collision_shape.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collision_batch.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collision_check.cpp
  ${CMAKE_CURRENT_LIST_DIR}/obstacle_index.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mesh_collision.cpp
  ${CMAKE_CURRENT_LIST_DIR}/path_check.cpp
  ${CMAKE_CURRENT_LIST_DIR}/waypoint_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frontier_cells.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frontier_tracker.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frontier_clusters.cpp
  ${CMAKE_CURRENT_LIST_DIR}/viewpoints.cpp
)
