#include <string>

#include "cuda_check.h"
#include "fragg_map/internal/cuda_backend_factory.h"

namespace fragg {

std::string cudaDeviceName(int device, std::string* why_not) {
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess) {
    (void)cudaGetLastError();
    if (why_not)
      *why_not = e == cudaErrorInsufficientDriver || e == cudaErrorNoDevice
                     ? std::string("no CUDA device or driver")
                     : std::string("no CUDA device: ") + cudaGetErrorString(e);
    return "";
  }
  if (device >= count) {
    if (why_not)
      *why_not =
          "no CUDA device " + std::to_string(device) + " (" + std::to_string(count) + " present)";
    return "";
  }
  cudaDeviceProp prop;
  if (cudaGetDeviceProperties(&prop, device) != cudaSuccess) {
    (void)cudaGetLastError();
    if (why_not) *why_not = "cannot query CUDA device " + std::to_string(device);
    return "";
  }
  return prop.name;
}

}  // namespace fragg
