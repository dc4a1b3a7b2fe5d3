// Every CUDA call is checked; a failure becomes a fragg::CudaError (CudaOutOfMemory when the
// device is out of memory) naming the call and where it was made.
#pragma once

#include <cuda_runtime.h>

#include "fragg_map/errors.h"

namespace fragg::cuda {

[[noreturn]] void throwCudaError(cudaError_t e, const char* call, const char* file, int line);

inline void check(cudaError_t e, const char* call, const char* file, int line) {
  if (e != cudaSuccess) throwCudaError(e, call, file, line);
}

}  // namespace fragg::cuda

#define FRAGG_CUDA_CHECK(call) ::fragg::cuda::check((call), #call, __FILE__, __LINE__)
/// After a kernel launch: launch-configuration errors are reported at once.
#define FRAGG_CUDA_CHECK_LAUNCH(kernel) \
  ::fragg::cuda::check(cudaGetLastError(), "launch of " kernel, __FILE__, __LINE__)
