# Simulator (fragg_map_sim_lib, ROS-free): scene primitives and scene files, sensors,
# trajectories, dataset writers and map quality against the scene. Meshes, the BVH and OBJ
# files come from fragg_map_geometry (src/geometry).
# FRAGG_SIM_ROS_SOURCES (the bag writer) go into fragg_map_sim_bag, built only with ROS.
set(FRAGG_SIM_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/primitives.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene_tiles.cpp
  ${CMAKE_CURRENT_LIST_DIR}/trajectory.cpp
  ${CMAKE_CURRENT_LIST_DIR}/movers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/lidar_sensor.cpp
  ${CMAKE_CURRENT_LIST_DIR}/depth_camera.cpp
  ${CMAKE_CURRENT_LIST_DIR}/dataset_writers.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_quality.cpp
  ${CMAKE_CURRENT_LIST_DIR}/dynamic_quality.cpp
)
set(FRAGG_SIM_ROS_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/bag_writer.cpp
)
