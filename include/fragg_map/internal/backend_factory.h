// Picks the backend a map integrates with: CPU, or CUDA when built with it and a device is
// present (`auto`), with one log line saying which and why.
#pragma once

#include <memory>
#include <string>

#include "fragg_map/internal/backend.h"
#include "fragg_map/map_params.h"

namespace fragg {

struct BackendChoice {
  std::unique_ptr<MapBackend> backend;
  std::string reason;  ///< e.g. "auto: CUDA device 0 (NVIDIA H100 80GB HBM3)"
};

/// Throws InvalidArgument when `cuda` is requested and cannot be had.
BackendChoice makeBackend(const MapParams& params);

/// True when this build has the CUDA backend (whether or not a device is present).
bool builtWithCuda();

/// Name of CUDA device `device`, or "" with `why_not` filled when there is none usable (or
/// the build has no CUDA backend).
std::string cudaDeviceName(int device, std::string* why_not);

}  // namespace fragg
