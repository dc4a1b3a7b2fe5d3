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
  ${CMAKE_CURRENT_LIST_DIR}/residency_kernels.cu
  ${CMAKE_CURRENT_LIST_DIR}/cuda_collision.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collision_kernels.cu
  ${CMAKE_CURRENT_LIST_DIR}/state_bits.cpp
  ${CMAKE_CURRENT_LIST_DIR}/state_bits_kernel.cu
  ${CMAKE_CURRENT_LIST_DIR}/viewpoint_gains.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gain_kernels.cu
)
# Eigen in device code (collision kernels): its defaulted special members draw warning 20012,
# its constexpr helpers need relaxed constexpr, its nvcc pragmas are unknown to g++.
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/collision_kernels.cu PROPERTIES
  COMPILE_OPTIONS "-diag-suppress=20012;--expt-relaxed-constexpr;-Xcompiler=-Wno-unknown-pragmas")
