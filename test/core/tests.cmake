# Test suites of src/core.
fragg_add_test(fragg_core_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/key_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/block_map_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/block_key_table_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/occupancy_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/raycast_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/insert_semantics_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/saturated_skip_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/insert_sequence_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/free_only_points_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/frustum_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/auto_sensor_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/map_file_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/map_lock_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/height_filter_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/field_names_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/extreme_points_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/free_box_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/map_memory_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/free_cut_cell_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/state_masks_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/change_log_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/host_view_gate_test.cpp
  LIBS fragg_map_core ZLIB::ZLIB
  LABELS core)
# Map::image + writeMapImage (the server's autosave) and the kill test: fragg_map_save_loop
# saves in a loop and is SIGKILLed at random moments.
add_executable(fragg_map_save_loop ${CMAKE_CURRENT_LIST_DIR}/map_save_loop.cpp)
target_link_libraries(fragg_map_save_loop fragg_map_core)
target_include_directories(fragg_map_save_loop PRIVATE ${CMAKE_CURRENT_LIST_DIR})
fragg_target_flags(fragg_map_save_loop)
fragg_add_test(fragg_core_map_image_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/map_image_test.cpp
  LIBS fragg_map_core
  LABELS core)
if(TARGET fragg_core_map_image_test)
  add_dependencies(fragg_core_map_image_test fragg_map_save_loop)
  target_compile_definitions(fragg_core_map_image_test PRIVATE
    FRAGG_SAVE_LOOP="$<TARGET_FILE:fragg_map_save_loop>")
endif()

# Dynamic-aware mapping (MapParams::dynamic) on the CPU backend against a brute-force reference,
# both rules (surround; pass-through, the default), decay, no-return beams of unorganised clouds.
fragg_add_test(fragg_dynamic_mapping_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/dynamic_mapping_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/dynamic_pass_through_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/dynamic_decay_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/dynamic_no_return_test.cpp
  LIBS fragg_map_core
  LABELS core)
