# Loop closure: the scan store, removal of scans and pose correction (issue 6).
fragg_add_test(fragg_loop_closure_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/unapply_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/scan_store_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/correction_test.cpp
  LIBS fragg_map_interop
  LABELS core loop)
