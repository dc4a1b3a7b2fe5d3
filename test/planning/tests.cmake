# fragg_map_planning: collision checks against brute force and independent overlap tests on
# hand-written maps, touching cases, unknown cells, margins, mesh insides, paths, bad inputs.
fragg_add_test(fragg_planning_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/collision_brute_force_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/collision_semantics_test.cpp
  LIBS fragg_map_planning
  LABELS planning)
