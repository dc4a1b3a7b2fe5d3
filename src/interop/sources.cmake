# Interop: exporters, renderer, map comparison (fragg_map_interop; libpng) and OctoMap
# .bt/.ot files (fragg_map_octomap; liboctomap). Also the CLI subcommands built on them.
set(FRAGG_INTEROP_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/export.cpp
  ${CMAKE_CURRENT_LIST_DIR}/compare.cpp
  ${CMAKE_CURRENT_LIST_DIR}/png_write.cpp
  ${CMAKE_CURRENT_LIST_DIR}/render_layout.cpp
  ${CMAKE_CURRENT_LIST_DIR}/render.cpp
  ${CMAKE_CURRENT_LIST_DIR}/render_legend.cpp
  ${CMAKE_CURRENT_LIST_DIR}/glyphs.cpp
)
set(FRAGG_OCTOMAP_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/octomap_export.cpp
  ${CMAKE_CURRENT_LIST_DIR}/octomap_file_check.cpp
  ${CMAKE_CURRENT_LIST_DIR}/octomap_tree_to_map.cpp
  ${CMAKE_CURRENT_LIST_DIR}/octomap_import.cpp
  ${CMAKE_CURRENT_LIST_DIR}/octomap_insert.cpp
)
# `fragg_map export | render | compare` and the map loader they share (src/tools/CMakeLists).
set(FRAGG_CLI_EXTRA_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/../tools/cli/map_input.cpp
  ${CMAKE_CURRENT_LIST_DIR}/../tools/cli/cmd_export.cpp
  ${CMAKE_CURRENT_LIST_DIR}/../tools/cli/cmd_render.cpp
  ${CMAKE_CURRENT_LIST_DIR}/../tools/cli/cmd_compare.cpp
)
