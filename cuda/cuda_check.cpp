#include "cuda_check.h"

#include <string>

namespace fragg::cuda {

void throwCudaError(cudaError_t e, const char* call, const char* file, int line) {
  (void)cudaGetLastError();  // clear a non-sticky error so the next call starts clean
  const std::string what = std::string("CUDA error in ") + call + " (" + file + ":" +
                           std::to_string(line) + "): " + cudaGetErrorName(e) + ": " +
                           cudaGetErrorString(e);
  if (e == cudaErrorMemoryAllocation) throw CudaOutOfMemory(what);
  throw CudaError(what);
}

}  // namespace fragg::cuda
