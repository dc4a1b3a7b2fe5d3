# Test suites of src/io (dataset readers). Real data from FRAGG_REAL_DATA.
fragg_add_test(io_point_file_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/point_file_test.cpp
  LIBS fragg_map_core
  LABELS io)

fragg_add_test(io_dataset_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/dataset_test.cpp
  LIBS fragg_map_core
  LABELS io)

# The ScanGraph parser is liboctomap-free; liboctomap only cross-checks it here.
if(octomap_FOUND)
  fragg_add_test(io_scan_graph_octomap_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/scan_graph_octomap_test.cpp
    LIBS fragg_map_core ${OCTOMAP_LIBRARIES}
    LABELS io)
  target_include_directories(io_scan_graph_octomap_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
endif()

# ROS bag reader: the test writes its bags at run time with make_test_bag.py (Debian's
# python3-rosbag), from the real small_gicp scans.
if(FRAGG_HAVE_ROS)
  fragg_add_test(io_rosbag_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/rosbag_source_test.cpp
    LIBS fragg_map_rosbag
    LABELS io ros)
  target_compile_definitions(io_rosbag_test PRIVATE
    FRAGG_MAKE_TEST_BAG="${CMAKE_CURRENT_LIST_DIR}/make_test_bag.py"
    FRAGG_PYTHON3="/usr/bin/python3")
endif()
