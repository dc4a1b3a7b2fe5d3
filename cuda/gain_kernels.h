// The gain kernels' arguments and launchers (gain_kernels.cu); no host-only header here, so
// the .cu file compiles without Eigen.
#pragma once

#include <cuda_runtime.h>

#include "device_types.h"
#include "fragg_map/internal/gain_walk.h"

namespace fragg::cuda {

struct GainKernelArgs {
  const unsigned long long* table_keys;  ///< packed block keys, kEmptyBlockKey = empty
  const int32_t* table_slots;
  uint64_t table_mask;
  const Block* slot_cells;
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

constexpr unsigned long long kEmptyBlockKey = ~0ULL;

/// Launchers (gain_kernels.cu).
void launchBlockTableBuild(const SlotArrays& slots, unsigned long long* keys, int32_t* table_slots,
                           uint64_t mask, cudaStream_t stream);
void launchViewpointGains(const GainKernelArgs& args, cudaStream_t stream);

}  // namespace fragg::cuda
