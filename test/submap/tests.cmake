# Sub-maps (issue 13): extract, truncate, merge and the .fgm region section.
fragg_add_test(fragg_submap_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/truncate_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/merge_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/refusal_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/submap_file_test.cpp
  LIBS fragg_map_interop ZLIB::ZLIB
  LABELS core submap)

# Runs the built `fragg_map` binary: truncate and merge, good and bad input.
fragg_add_test(cli_submap_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/cli_submap_test.cpp
  LIBS fragg_map_interop nlohmann_json::nlohmann_json
  LABELS cli submap)
if(TARGET cli_submap_test)
  add_dependencies(cli_submap_test fragg_map_cli)
  target_compile_definitions(cli_submap_test PRIVATE FRAGG_CLI_PATH="$<TARGET_FILE:fragg_map_cli>")
  target_include_directories(cli_submap_test PRIVATE ${CMAKE_CURRENT_LIST_DIR}/../interop)
endif()

# The same edits on the CUDA backend (label gpu; skipped without a device).
fragg_add_test(fragg_gpu_submap_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/submap_gpu_test.cpp
  LIBS fragg_map_interop
  LABELS gpu submap)
