# ROS-free planning queries over a map (fragg_map_planning): collision checks of boxes, spheres,
# capsules and triangle meshes (single poses, OpenMP or CUDA batches, paths), waypoint files;
# frontier cells (full and incremental), coarse frontier grids and the beam spacing that sizes
# them, clusters, viewpoints and information gain or coverage.
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
  ${CMAKE_CURRENT_LIST_DIR}/coarse_map.cpp
  ${CMAKE_CURRENT_LIST_DIR}/beam_spacing.cpp
  ${CMAKE_CURRENT_LIST_DIR}/viewpoints.cpp
)

# Planning's CUDA part (fragg_map_planning_cuda, CUDA builds only): the collision, gain and
# frontier-tracker kernels over the map's device layer view (or an uploaded obstacle index).
set(FRAGG_PLANNING_CUDA_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/cuda/cuda_collision.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cuda/collision_kernels.cu
  ${CMAKE_CURRENT_LIST_DIR}/cuda/viewpoint_gains.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cuda/gain_kernels.cu
  ${CMAKE_CURRENT_LIST_DIR}/cuda/device_frontiers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cuda/frontier_kernels.cu
)
# Eigen in device code (collision kernels): its defaulted special members draw warning 20012,
# its constexpr helpers need relaxed constexpr, its nvcc pragmas are unknown to g++.
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/cuda/collision_kernels.cu PROPERTIES
  COMPILE_OPTIONS "-diag-suppress=20012;--expt-relaxed-constexpr;-Xcompiler=-Wno-unknown-pragmas")
