# Agreement with OctoMap (needs liboctomap): the same real scans through both.
if(octomap_FOUND)
  fragg_add_test(fragg_agreement_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/octomap_agreement_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/octomap_keys_test.cpp
    LIBS fragg_map_core ${OCTOMAP_LIBRARIES}
    LABELS agreement)
  target_include_directories(fragg_agreement_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
endif()

# fragg_map build (bag) -> export .bt, against OctoMap on the same bag (needs ROS for bags).
if(octomap_FOUND AND FRAGG_HAVE_ROS AND TARGET fragg_map_rosbag)
  fragg_add_test(fragg_cli_bag_agreement_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/cli_bag_agreement_test.cpp
    LIBS fragg_map_rosbag ${OCTOMAP_LIBRARIES}
    LABELS agreement ros)
  target_include_directories(fragg_cli_bag_agreement_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
  target_compile_definitions(fragg_cli_bag_agreement_test PRIVATE
    FRAGG_CLI="$<TARGET_FILE:fragg_map_cli>"
    FRAGG_MAKE_TEST_BAG="${PROJECT_SOURCE_DIR}/test/io/make_test_bag.py"
    FRAGG_PYTHON3="/usr/bin/python3")
  add_dependencies(fragg_cli_bag_agreement_test fragg_map_cli)
endif()
