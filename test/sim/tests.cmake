# Simulator and map-quality suites: scenes and primitives (analytic ray hits, OBJ meshes in a
# scene, scene files), sensors (NaN for no return, noise and dropout statistics), determinism,
# evaluation metrics on a hand-made map, and (ROS builds) the bag read back by the core's bag
# reader. The mesh, BVH and OBJ code itself is tested in test/geometry.
fragg_add_test(sim_scene_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/scene_test.cpp
  LIBS fragg_map_sim_lib
  LABELS sim)

fragg_add_test(sim_sensor_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/sensor_test.cpp
  LIBS fragg_map_sim_lib
  LABELS sim)

fragg_add_test(sim_map_quality_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/map_quality_test.cpp
  LIBS fragg_map_sim_lib
  LABELS sim)

if(TARGET fragg_map_sim_bag AND TARGET fragg_map_rosbag)
  fragg_add_test(sim_bag_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/bag_test.cpp
    LIBS fragg_map_sim_bag fragg_map_rosbag
    LABELS sim ros)
  add_dependencies(sim_bag_test fragg_map_smoke_workload)
  target_compile_definitions(sim_bag_test PRIVATE FRAGG_SMOKE_BAG="${FRAGG_SMOKE_BAG}")
endif()

# Runs the built fragg_map_sim and fragg_map (eval, octomap-build) on the smoke workload.
fragg_add_test(sim_cli_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/cli_sim_eval_test.cpp
  LIBS fragg_map_core nlohmann_json::nlohmann_json
  LABELS sim cli)
if(TARGET sim_cli_test)
  add_dependencies(sim_cli_test fragg_map_cli fragg_map_sim fragg_map_smoke_workload)
  target_compile_definitions(sim_cli_test PRIVATE
    FRAGG_CLI_PATH="$<TARGET_FILE:fragg_map_cli>"
    FRAGG_SIM_PATH="$<TARGET_FILE:fragg_map_sim>"
    FRAGG_SMOKE_DIR="${FRAGG_SMOKE_DIR}"
    FRAGG_SCENES_DIR="${PROJECT_SOURCE_DIR}/config/scenes"
    $<$<TARGET_EXISTS:fragg_map_octomap>:FRAGG_CLI_HAS_OCTOMAP=1>)
endif()

# W4's scene and loop (not the 1.5 GB recording): scene file, trajectory length, one coarse scan.
fragg_add_test(sim_long_drive_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/long_drive_test.cpp
  LIBS fragg_map_sim_lib
  LABELS sim)
if(TARGET sim_long_drive_test)
  target_compile_definitions(sim_long_drive_test PRIVATE
    FRAGG_SCENES_DIR="${PROJECT_SOURCE_DIR}/config/scenes"
    FRAGG_WORKLOADS_CONFIG_DIR="${PROJECT_SOURCE_DIR}/config/workloads")
endif()

# Movers: scripted poses, scene files with movers, per-point dynamic labels and their files.
fragg_add_test(sim_movers_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/movers_test.cpp
  LIBS fragg_map_sim_lib
  LABELS sim)
