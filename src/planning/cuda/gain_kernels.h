// The gain kernels' arguments and launchers (gain_kernels.cu); no host-only header here, so
// the .cu file compiles without Eigen.
#pragma once

#include <cuda_runtime.h>

#include "../gain_walk.h"
#include "fragg_map/device_layer_view.h"
#include "fragg_map/occupancy.h"

namespace fragg::cuda {

struct GainKernelArgs {
  DeviceLayerView view;  ///< the map's blocks on the device
  OccupancyModel model;
  const double* origins_v;  ///< this round's viewpoints
  const double* cos_yaw;
  const double* sin_yaw;
  const double* rays;
  uint32_t rays_per_viewpoint;
  uint32_t viewpoints;
  double length_v;
  int half;  ///< the bitmap cube spans origin cell +- half
  uint64_t words_per_viewpoint;
  unsigned long long* seen;  ///< bitmaps, words_per_viewpoint each
  double* gains;
};

/// Launcher (gain_kernels.cu).
void launchViewpointGains(const GainKernelArgs& args, cudaStream_t stream);

}  // namespace fragg::cuda
