# fragg_map_geometry on its own (no simulator): triangle queries against analytic values, the
# mesh BVH against brute force and analytic boxes, mesh appends, OBJ files.
fragg_add_test(fragg_geometry_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/triangle_queries_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/triangle_mesh_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/mesh_bvh_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/obj_file_test.cpp
  LIBS fragg_map_geometry
  LABELS geometry)
