# ROS-free geometry (fragg_map_geometry): triangle meshes of closed solids, Wavefront OBJ files
# and the mesh BVH (ray hits, distance, inside). Used by the simulator and, later, collision
# checking; depends on fragg_map_core and Eigen only.
set(FRAGG_GEOMETRY_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/triangle_mesh.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mesh_bvh.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mesh_primitives.cpp
  ${CMAKE_CURRENT_LIST_DIR}/obj_file.cpp
)
