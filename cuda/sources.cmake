# The CUDA backend. slot_table.cpp and host_only_index.cpp are plain C++ (no CUDA runtime):
# they are also built into the CPU-side unit tests (test/cache/).
set(FRAGG_CUDA_HOST_LOGIC_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/slot_table.cpp
  ${CMAKE_CURRENT_LIST_DIR}/host_only_index.cpp
)
set(FRAGG_CUDA_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/cuda_check.cpp
  ${CMAKE_CURRENT_LIST_DIR}/device_query.cpp
  ${CMAKE_CURRENT_LIST_DIR}/pinned_allocator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/slot_pool.cpp
  ${CMAKE_CURRENT_LIST_DIR}/block_transfer.cpp
  ${CMAKE_CURRENT_LIST_DIR}/device_block_cache.cpp
  ${CMAKE_CURRENT_LIST_DIR}/window_table.cpp
  ${CMAKE_CURRENT_LIST_DIR}/device_scan.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cuda_integrator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cuda_backend.cpp
  ${CMAKE_CURRENT_LIST_DIR}/prepare_kernel.cu
  ${CMAKE_CURRENT_LIST_DIR}/auto_sensor_kernel.cu
  ${CMAKE_CURRENT_LIST_DIR}/raycast_kernel.cu
  ${CMAKE_CURRENT_LIST_DIR}/apply_kernel.cu
  ${CMAKE_CURRENT_LIST_DIR}/dynamic_kernels.cu
  ${CMAKE_CURRENT_LIST_DIR}/residency_kernels.cu
  ${CMAKE_CURRENT_LIST_DIR}/device_scratch.cpp
  ${CMAKE_CURRENT_LIST_DIR}/layer_view.cpp
  ${CMAKE_CURRENT_LIST_DIR}/layer_view_kernels.cu
)
