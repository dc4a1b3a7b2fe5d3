# Test suites of src/interop and of the CLI subcommands built on it. The maps are made by
# hand (cells set through Map::writeCells), so nothing here depends on the ray caster.
fragg_add_test(interop_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/export_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/render_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/render_legend_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/compare_test.cpp
  LIBS fragg_map_interop PNG::PNG
  LABELS interop)
if(TARGET interop_test)
  # The legend's font (src/interop/glyphs.h) is tested directly.
  target_include_directories(interop_test PRIVATE ${PROJECT_SOURCE_DIR}/src/interop)
endif()

if(TARGET fragg_map_octomap)
  fragg_add_test(interop_octomap_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/octomap_io_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/octomap_full_test.cpp
    LIBS fragg_map_octomap fragg_map_interop
    LABELS interop octomap)
endif()

# Runs the built `fragg_map` binary (export / render / compare, good and bad input; render
# --highlight-ghosts).
fragg_add_test(interop_cli_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/cli_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/cli_render_ghosts_test.cpp
  LIBS fragg_map_core nlohmann_json::nlohmann_json PNG::PNG
  LABELS interop cli)
if(TARGET interop_cli_test)
  add_dependencies(interop_cli_test fragg_map_cli)
  target_compile_definitions(interop_cli_test PRIVATE
    FRAGG_CLI_PATH="$<TARGET_FILE:fragg_map_cli>"
    $<$<TARGET_EXISTS:fragg_map_octomap>:FRAGG_CLI_HAS_OCTOMAP=1>)
endif()

# Runs the built `fragg_map` binary: build and stats, good and bad input.
fragg_add_test(cli_build_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/cli_build_test.cpp
  LIBS fragg_map_core nlohmann_json::nlohmann_json
  LABELS cli)
if(TARGET cli_build_test)
  add_dependencies(cli_build_test fragg_map_cli)
  target_compile_definitions(cli_build_test PRIVATE FRAGG_CLI_PATH="$<TARGET_FILE:fragg_map_cli>")
endif()
