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
  /// Viewpoint i's cell bitmap covers the cells box_lo[3i..3i+2] + [0, box_dims) (voxel keys):
  /// every cell its rays can enter (seenBoxes).
  const int32_t* box_lo;
  int32_t box_dims[3];
  uint64_t words_per_viewpoint;
  unsigned long long* seen;  ///< bitmaps, words_per_viewpoint each
  double* gains;
  /// Optional dense block table over the batch's reach: the slot of block dense_lo + (x, y, z)
  /// at ((z * dims[1]) + y) * dims[0] + x, kNoViewSlot where none; nullptr: the view's hash.
  const int32_t* dense = nullptr;
  BlockKey dense_lo{0, 0, 0};
  int32_t dense_dims[3] = {0, 0, 0};
};

/// Launcher (gain_kernels.cu).
void launchViewpointGains(const GainKernelArgs& args, cudaStream_t stream);

/// Fills `table` (dims[0] * dims[1] * dims[2] entries) with the slot of every block of `view`
/// in the box lo + [0, dims), kNoViewSlot elsewhere.
void launchDenseBlockTable(const DeviceLayerView& view, BlockKey lo, const int32_t dims[3],
                           int32_t* table, cudaStream_t stream);

}  // namespace fragg::cuda
