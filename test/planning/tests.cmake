# fragg_map_planning: collision checks against brute force and independent overlap tests on
# hand-written maps, touching cases, unknown cells, margins, mesh insides, paths, bad inputs.
fragg_add_test(fragg_planning_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/collision_brute_force_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/collision_semantics_test.cpp
  LIBS fragg_map_planning
  LABELS planning)

# Runs the built `fragg_map collide` on a hand-written map saved as .fgm.
fragg_add_test(cli_collide_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/cli_collide_test.cpp
  LIBS fragg_map_core fragg_map_geometry nlohmann_json::nlohmann_json PNG::PNG
  LABELS cli planning)
if(TARGET cli_collide_test)
  add_dependencies(cli_collide_test fragg_map_cli)
  target_compile_definitions(cli_collide_test PRIVATE FRAGG_CLI_PATH="$<TARGET_FILE:fragg_map_cli>")
  target_include_directories(cli_collide_test PRIVATE ${CMAKE_CURRENT_LIST_DIR}/../interop)
endif()

# FCL as an oracle on a real scan, only when FCL (libfcl-dev, scripts/install_deps.sh) is found.
find_package(fcl QUIET)
if(fcl_FOUND)
  fragg_add_test(fcl_oracle_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/fcl_oracle_test.cpp
    LIBS fragg_map_planning fcl
    LABELS planning)
else()
  message(STATUS "fragg_map: FCL not found: no FCL oracle test for collision checking")
endif()

# Frontier cells against a brute force, incremental against full over a simulated drive,
# clusters, viewpoints and gains against a brute-force ray count; coverage gains against a
# brute-force visibility count, coarse copies of a box, beam spacings of simulated LiDARs.
fragg_add_test(fragg_frontier_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/frontier_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/coarse_query_test.cpp
  LIBS fragg_map_planning fragg_map_sim_lib
  LABELS planning)
if(TARGET fragg_frontier_test)
  target_compile_definitions(fragg_frontier_test PRIVATE FRAGG_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  # gain_walk.h: the index arithmetic the CUDA gain kernels share with the host.
  target_include_directories(fragg_frontier_test PRIVATE ${PROJECT_SOURCE_DIR}/src/planning)
endif()

# Runs the built `fragg_map frontiers` and `render --frontiers` on hand-written maps saved as .fgm.
fragg_add_test(cli_frontiers_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/cli_frontiers_test.cpp
  LIBS fragg_map_planning nlohmann_json::nlohmann_json PNG::PNG
  LABELS cli planning)
if(TARGET cli_frontiers_test)
  add_dependencies(cli_frontiers_test fragg_map_cli)
  target_compile_definitions(cli_frontiers_test PRIVATE FRAGG_CLI_PATH="$<TARGET_FILE:fragg_map_cli>")
  target_include_directories(cli_frontiers_test PRIVATE ${CMAKE_CURRENT_LIST_DIR}/../interop)
endif()

# fragg_map_explore's loop in a small room (explored volume grows, deterministic CSV, clear
# viewpoints, reference cells against brute force) and bad arguments of the executable.
fragg_add_test(fragg_explore_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/explore_test.cpp
  LIBS fragg_map_explore_lib
  LABELS planning)
if(TARGET fragg_explore_test)
  add_dependencies(fragg_explore_test fragg_map_explore)
  target_compile_definitions(fragg_explore_test PRIVATE
    FRAGG_CLI_PATH="$<TARGET_FILE:fragg_map_explore>")
  target_include_directories(fragg_explore_test PRIVATE ${CMAKE_CURRENT_LIST_DIR}/../interop)
endif()
