# Loop closure: the scan store, removal of scans and pose correction (issue 6).
fragg_add_test(fragg_loop_closure_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/unapply_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/scan_store_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/correction_test.cpp
  LIBS fragg_map_interop
  LABELS core loop)

# Runs the built `fragg_map` binary: build --keep-scans, stats --scans, correct.
fragg_add_test(cli_correct_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/cli_correct_test.cpp
  LIBS fragg_map_core nlohmann_json::nlohmann_json
  LABELS cli loop)
if(TARGET cli_correct_test)
  add_dependencies(cli_correct_test fragg_map_cli)
  target_compile_definitions(cli_correct_test PRIVATE FRAGG_CLI_PATH="$<TARGET_FILE:fragg_map_cli>")
  target_include_directories(cli_correct_test PRIVATE ${CMAKE_CURRENT_LIST_DIR}/../interop)
endif()
