// The gain kernels' arguments and launchers (gain_kernels.cu); no host-only header here, so
// the .cu file compiles without Eigen.
#pragma once

#include <cuda_runtime.h>

#include "../gain_walk.h"
#include "fragg_map/device_layer_view.h"
#include "fragg_map/occupancy.h"

namespace fragg::cuda {

/// What every gain kernel reads of a round: the map's view, the model, the round's viewpoints
/// and the sensor's rays.
struct GainRound {
  DeviceLayerView view;  ///< the map's blocks on the device
  OccupancyModel model;
  const double* origins_v;  ///< this round's viewpoints
  const double* cos_yaw;
  const double* sin_yaw;
  const double* rays;
  uint32_t rays_per_viewpoint;
  uint32_t viewpoints;  ///< viewpoints * rays_per_viewpoint < 2^32
  double length_v;
};

/// The plain gain kernel's arguments (launchViewpointGains): every viewpoint's bitmap of one size.
struct GainKernelArgs : GainRound {
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

/// Whose a taken pool bitmap is (the deferred kernel's second pass): the viewpoint (index in
/// its round) and the map block.
struct alignas(16) PoolOwner {
  uint32_t vp;
  int32_t x, y, z;
};

/// The sized, pooled and queued gain kernels' arguments (launchGainWalk): as GainKernelArgs,
/// with each viewpoint's box of its own size and the seen cells kept densely (a bitmap a
/// viewpoint) or by block (a directory a viewpoint over its box's blocks, block bitmaps from a
/// pool).
struct GainWalkArgs : GainRound {
  /// Viewpoint i's box: the cells box_lo[3i..3i+2] + [0, box_dims[3i..3i+2]) (voxel keys),
  /// every cell its rays can enter (seenBoxes).
  const int32_t* box_lo;
  const int32_t* box_dims;
  /// Dense: viewpoint i's bitmap starts at seen + seen_offset[i] (64-bit words).
  const uint64_t* seen_offset = nullptr;
  unsigned long long* seen = nullptr;
  /// Pooled: viewpoint i's directory starts at directory + directory_offset[i]; its entries
  /// cover the blocks of its box (PoolDirectory::over(box_lo + 3i, box_dims + 3i); entries as
  /// gain_walk.h's kPoolEmpty etc.). Bitmaps of 8 words (one block's 512 cells) in `pool`,
  /// `pool_blocks` of them; `pool_taken` counts those taken; overflow[i] is set when viewpoint i
  /// met a full pool.
  const uint64_t* directory_offset = nullptr;
  uint32_t* directory = nullptr;
  unsigned long long* pool = nullptr;
  uint32_t pool_blocks = 0;
  unsigned int* pool_taken = nullptr;
  uint32_t* overflow = nullptr;
  /// Deferred: the owner of each taken bitmap (pool_blocks entries).
  PoolOwner* pool_owner = nullptr;
  /// Queued: the rays handed out after the first (one a launched thread), 0 at launch; a warp
  /// takes new rays once `refill_lanes` lanes are idle.
  unsigned long long* queue = nullptr;
  int refill_lanes = 4;
  double* gains = nullptr;
  /// Optional dense block table, as GainKernelArgs's.
  const int32_t* dense = nullptr;
  BlockKey dense_lo{0, 0, 0};
  int32_t dense_dims[3] = {0, 0, 0};
};

/// Launcher of the sized (dense, one thread a ray), pooled (`pooled`) and queued (`queued`:
/// persistent threads, as many as the device holds at once) walks; `deferred` (only with
/// `pooled` and `queued`, the callers' duty): the walk only sets the seen bits, and a second kernel
/// sums the entropy of the cells set in the round's taken bitmaps into their viewpoints' gains
/// (gain_kernels.cu).
void launchGainWalk(const GainWalkArgs& args, bool pooled, bool queued, bool deferred,
                    cudaStream_t stream);

/// Fills `table` (dims[0] * dims[1] * dims[2] entries) with the slot of every block of `view`
/// in the box lo + [0, dims), kNoViewSlot elsewhere.
void launchDenseBlockTable(const DeviceLayerView& view, BlockKey lo, const int32_t dims[3],
                           int32_t* table, cudaStream_t stream);

}  // namespace fragg::cuda
