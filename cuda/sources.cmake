set(FRAGG_CUDA_SOURCES ${CMAKE_CURRENT_LIST_DIR} / cuda_check.cpp ${CMAKE_CURRENT_LIST_DIR} /
    device_query.cpp ${CMAKE_CURRENT_LIST_DIR} / pinned_allocator.cpp ${CMAKE_CURRENT_LIST_DIR} /
    slot_pool.cpp ${CMAKE_CURRENT_LIST_DIR} / host_only_index.cpp ${CMAKE_CURRENT_LIST_DIR} /
    cuda_integrator.cpp ${CMAKE_CURRENT_LIST_DIR} / prepare_kernel.cu ${CMAKE_CURRENT_LIST_DIR} /
    raycast_kernel.cu ${CMAKE_CURRENT_LIST_DIR} / apply_kernel.cu ${CMAKE_CURRENT_LIST_DIR} /
    residency_kernels.cu)
