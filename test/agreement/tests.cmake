# Agreement with OctoMap (needs liboctomap): the same real scans through both.
if(octomap_FOUND)
  fragg_add_test(fragg_agreement_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/octomap_agreement_test.cpp
    LIBS fragg_map_core ${OCTOMAP_LIBRARIES}
    LABELS agreement)
  target_include_directories(fragg_agreement_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
endif()
