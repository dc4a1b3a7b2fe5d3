// Entry points of the CUDA backend (defined in cuda/, linked only when built with CUDA).
#pragma once

#include <memory>
#include <string>

#include "fragg_map/internal/backend.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/map_params.h"

namespace fragg {

/// Throws CudaError when the device cannot be set up.
std::unique_ptr<MapBackend> makeCudaBackend(const MapParams& params);

}  // namespace fragg
