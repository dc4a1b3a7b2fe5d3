# Test suites of src/core.
fragg_add_test(fragg_core_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/key_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/block_map_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/occupancy_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/raycast_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/insert_semantics_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/saturated_skip_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/free_only_points_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/frustum_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/map_file_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/map_lock_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/height_filter_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/field_names_test.cpp
  LIBS fragg_map_core ZLIB::ZLIB
  LABELS core)
