# The CUDA backend against the CPU backend (label gpu). Built wherever the core is; the tests
# that need a device skip themselves without one.
fragg_add_test(fragg_gpu_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/cuda_backend_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/extreme_points_gpu_test.cpp
          ${CMAKE_CURRENT_LIST_DIR}/free_box_gpu_test.cpp
          ${PROJECT_SOURCE_DIR}/test/fuzz/insert_input.cpp
          ${PROJECT_SOURCE_DIR}/src/tools/bench/synthetic_lidar.cpp
  LIBS fragg_map_core fragg_map_sim_lib
  LABELS gpu)
target_include_directories(fragg_gpu_test PRIVATE ${PROJECT_SOURCE_DIR}/src/tools)
target_compile_definitions(fragg_gpu_test PRIVATE FRAGG_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
  FRAGG_FUZZ_CORPUS="${PROJECT_SOURCE_DIR}/test/fuzz/corpus")

# The device block cache on its own (needs the CUDA headers: CUDA builds only).
if(FRAGG_HAVE_CUDA)
  fragg_add_test(fragg_gpu_cache_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/device_block_cache_test.cpp
    LIBS fragg_map_core CUDA::cudart_static
    LABELS gpu)
  target_include_directories(fragg_gpu_cache_test PRIVATE ${PROJECT_SOURCE_DIR}/cuda)
endif()

# Out-of-core paging on the CUDA backend (needs the page stores: SQLite + zstd, staged on the
# GPU machine under .device/store by ../shared/tools/stage-store.sh).
if(TARGET fragg_map_store)
  fragg_add_test(fragg_gpu_paging_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/paging_gpu_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/dynamic_paging_gpu_test.cpp
    LIBS fragg_map_store
    LABELS gpu paging)
endif()

# The CUDA collision checker against the CPU one (all shapes, options, paths; skips without a
# device; built in every build: without CUDA it checks that cuda is refused and auto falls back).
fragg_add_test(fragg_gpu_collision_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/collision_gpu_test.cpp
  LIBS fragg_map_planning
  LABELS gpu)

# Frontiers on the CUDA backend (cell states read over the device block cache) against the
# CPU backend over a simulated drive; skips without a device.
fragg_add_test(fragg_gpu_frontier_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/frontier_gpu_test.cpp
  LIBS fragg_map_planning fragg_map_sim_lib
  LABELS gpu)
target_compile_definitions(fragg_gpu_frontier_test PRIVATE FRAGG_SOURCE_DIR="${PROJECT_SOURCE_DIR}")

# The state-mask layer on the CUDA backend against the CPU backend (after every scan of a drive,
# each named edit, paging when the page stores are built); skips without a device.
fragg_add_test(fragg_gpu_state_masks_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/state_masks_gpu_test.cpp
          ${PROJECT_SOURCE_DIR}/src/tools/bench/synthetic_lidar.cpp
  LIBS fragg_map_core fragg_map_sim_lib
  LABELS gpu)
target_include_directories(fragg_gpu_state_masks_test PRIVATE ${PROJECT_SOURCE_DIR}/src/tools)
if(TARGET fragg_map_store AND TARGET fragg_gpu_state_masks_test)
  target_link_libraries(fragg_gpu_state_masks_test fragg_map_store)
  target_compile_definitions(fragg_gpu_state_masks_test PRIVATE FRAGG_HAVE_STORE)
endif()

# Dynamic-aware mapping (MapParams::dynamic) on the CUDA backend against the CPU backend: the
# labelled room under both rules, a W6 slice with a small pool; skips without a device.
fragg_add_test(fragg_gpu_dynamic_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/dynamic_gpu_test.cpp
  LIBS fragg_map_core fragg_map_sim_lib
  LABELS gpu)
target_compile_definitions(fragg_gpu_dynamic_test PRIVATE FRAGG_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
