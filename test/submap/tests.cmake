# Sub-maps (issue 13): extract, truncate, merge and the .fgm region section.
fragg_add_test(fragg_submap_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/truncate_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/merge_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/refusal_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/submap_file_test.cpp
  LIBS fragg_map_interop ZLIB::ZLIB
  LABELS core submap)
