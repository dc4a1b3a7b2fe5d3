# The device block cache's host-side book-keeping (cuda/slot_table, cuda/host_only_index) and
# the auto sensor model's device accumulators (cuda/auto_stats_accum.h): plain C++, tested
# without a device. The device side is in test/gpu.
fragg_add_test(fragg_cache_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/slot_table_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/host_only_index_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/auto_stats_accum_test.cpp
  LIBS fragg_map_core
  LABELS core)
target_include_directories(fragg_cache_test PRIVATE ${PROJECT_SOURCE_DIR}/cuda)
