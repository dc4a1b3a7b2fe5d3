// The gain walk over the map's device layer view (one thread per viewpoint and ray).
#include "cuda_check.h"
#include "gain_kernels.h"

namespace fragg::cuda {

namespace {

/// The slot of block `b` (kNoViewSlot: none): the dense table where the batch has one (and b
/// lies in it), else the view's hash.
__device__ int32_t gainSlot(const GainKernelArgs& a, const BlockKey& b) {
  if (a.dense) {
    const int64_t x = int64_t(b.x) - a.dense_lo.x, y = int64_t(b.y) - a.dense_lo.y,
                  z = int64_t(b.z) - a.dense_lo.z;
    if (x >= 0 && y >= 0 && z >= 0 && x < a.dense_dims[0] && y < a.dense_dims[1] &&
        z < a.dense_dims[2]) {
      return a.dense[(z * a.dense_dims[1] + y) * a.dense_dims[0] + x];
    }
  }
  return a.view.findSlot(b);
}

__global__ void denseBlockTableKernel(DeviceLayerView view, BlockKey lo, int32_t dx, int32_t dy,
                                      int32_t dz, int32_t* table) {
  const uint64_t i = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i > view.table_mask) return;
  const int32_t s = view.table[i];
  if (s == kNoViewSlot) return;
  const BlockKey k = view.slot_keys[s];
  const int64_t x = int64_t(k.x) - lo.x, y = int64_t(k.y) - lo.y, z = int64_t(k.z) - lo.z;
  if (x < 0 || y < 0 || z < 0 || x >= dx || y >= dy || z >= dz) return;
  table[(z * dy + y) * dx + x] = s;
}

__global__ void viewpointGainsKernel(GainKernelArgs a) {
  const uint64_t idx = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  const uint64_t total = uint64_t(a.viewpoints) * a.rays_per_viewpoint;
  double gain = 0.0;
  uint32_t vp = 0;
  if (idx < total) {
    vp = static_cast<uint32_t>(idx / a.rays_per_viewpoint);
    const uint32_t r = static_cast<uint32_t>(idx % a.rays_per_viewpoint);
    double dir[3];
    yawRotate(a.cos_yaw[vp], a.sin_yaw[vp], a.rays + 3 * r, dir);
    const double* origin = a.origins_v + 3 * vp;
    GainWalk walk = GainWalk::along(origin, dir, a.length_v);
    const int64_t bx = a.box_lo[3 * vp], by = a.box_lo[3 * vp + 1], bz = a.box_lo[3 * vp + 2];
    const int64_t sx = a.box_dims[0], sy = a.box_dims[1], sz = a.box_dims[2];
    unsigned long long* seen = a.seen + vp * a.words_per_viewpoint;
    // States from the slot's masks (128 bytes a block, shared by every ray crossing it), the
    // occupied and free words of the cell's z slice of the block kept while the ray stays in it
    // (a near-horizontal ray loads them once a block); a cell itself is read only when an
    // unknown one is first seen (its entropy).
    int32_t slot = kNoViewSlot;
    int slice = -1;
    uint64_t occupied_word = 0, free_word = 0;
    for (int entry = kUnknownBlock;; entry = walk.next()) {
      const VoxelKey k = walk.cell();
      if (entry != kSameBlock) {
        slot = gainSlot(a, blockKeyOf(k));
        slice = -1;
      }
      const int c = cellIndexOf(k);
      if ((c >> 6) != slice) {
        slice = c >> 6;
        occupied_word = slot == kNoViewSlot ? 0 : a.view.masks[slot].occupied[slice];
        free_word = slot == kNoViewSlot ? 0 : a.view.masks[slot].free[slice];
      }
      const uint64_t cell_bit = uint64_t{1} << (c & 63);
      const CellState s = (occupied_word & cell_bit) ? CellState::kOccupied
                          : (free_word & cell_bit)   ? CellState::kFree
                                                     : CellState::kUnknown;
      if (s == CellState::kOccupied) break;
      if (s == CellState::kUnknown) {
        const int64_t lx = k.x - bx, ly = k.y - by, lz = k.z - bz;
        if (lx >= 0 && ly >= 0 && lz >= 0 && lx < sx && ly < sy && lz < sz) {
          const uint64_t bit = uint64_t((lz * sy + ly) * sx + lx);
          const unsigned long long mask = 1ULL << (bit & 63);
          if (!(atomicOr(&seen[bit >> 6], mask) & mask))
            gain +=
                cellGainBits(a.model, slot == kNoViewSlot ? nullptr : &a.view.cells[slot].cells[c]);
        }
      }
      if (walk.done()) break;
    }
  }
  // Rays of one viewpoint are consecutive: sum within the warp where all lanes share it.
  const uint32_t first_vp = __shfl_sync(0xffffffffu, vp, 0);
  const bool shared = __all_sync(0xffffffffu, vp == first_vp);
  if (shared) {
    for (int offset = 16; offset > 0; offset /= 2)
      gain += __shfl_down_sync(0xffffffffu, gain, offset);
    if ((threadIdx.x & 31) == 0 && gain != 0.0) atomicAdd(&a.gains[vp], gain);
  } else if (idx < total && gain != 0.0) {
    atomicAdd(&a.gains[vp], gain);
  }
}

}  // namespace

void launchViewpointGains(const GainKernelArgs& args, cudaStream_t stream) {
  const uint64_t total = uint64_t(args.viewpoints) * args.rays_per_viewpoint;
  if (total == 0) return;
  constexpr int kThreads = 128;
  const uint64_t grid = (total + kThreads - 1) / kThreads;
  viewpointGainsKernel<<<static_cast<unsigned>(grid), kThreads, 0, stream>>>(args);
  FRAGG_CUDA_CHECK(cudaGetLastError());
}

void launchDenseBlockTable(const DeviceLayerView& view, BlockKey lo, const int32_t dims[3],
                           int32_t* table, cudaStream_t stream) {
  const size_t entries = size_t(dims[0]) * dims[1] * dims[2];
  FRAGG_CUDA_CHECK(cudaMemsetAsync(table, 0xff, entries * sizeof(int32_t), stream));
  if (view.table == nullptr) return;
  constexpr int kThreads = 256;
  const uint64_t grid = (uint64_t(view.table_mask) + kThreads) / kThreads;
  denseBlockTableKernel<<<static_cast<unsigned>(grid), kThreads, 0, stream>>>(
      view, lo, dims[0], dims[1], dims[2], table);
  FRAGG_CUDA_CHECK(cudaGetLastError());
}

}  // namespace fragg::cuda
