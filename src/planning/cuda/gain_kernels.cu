// The gain walks over the map's device layer view: the plain kernel (one thread per viewpoint
// and ray, a dense bitmap a viewpoint of the largest box's size) and the sized, pooled and
// queued variants (GainKernel).
#include <algorithm>
#include <cuda/atomic>

#include "cuda_check.h"
#include "gain_kernels.h"

namespace fragg::cuda {

namespace {

/// The slot of block `b` (kNoViewSlot: none): the dense table where the batch has one (and b
/// lies in it), else the view's hash. `Args`: GainKernelArgs or GainWalkArgs.
template <class Args>
__device__ int32_t gainSlot(const Args& a, const BlockKey& b) {
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

constexpr unsigned kFullWarp = 0xffffffffu;
/// Steps a lane of a queued kernel walks between its warp's looks at the idle lanes.
constexpr int kQueueBurst = 8;
constexpr int kWalkThreads = 128;
/// Blocks an SM should hold: caps the walks at 64 registers (the plain kernel uses 72: 7 blocks).
/// FRAGG_GAIN_WALK_BLOCKS_PER_SM (a compile definition) overrides it, to time the walks at
/// other register caps (ptxas -v, nvcc 13, sm_90: 10 gives 48 registers with 20-98 bytes of
/// spill stores a kernel, pooled-deferred the least; 12 gives 40 with 60-206).
#ifdef FRAGG_GAIN_WALK_BLOCKS_PER_SM
constexpr int kWalkBlocksPerSm = FRAGG_GAIN_WALK_BLOCKS_PER_SM;
#else
constexpr int kWalkBlocksPerSm = 8;
#endif

/// One ray's walk in a sized, pooled or queued kernel: the DDA, the current block's slot and
/// the cell's z slice of its masks (as the plain kernel keeps them), and where its seen cells
/// go: the viewpoint's dense bitmap and box (cells), or the current block's pool bitmap (the
/// pooled kernels look the viewpoint's directory up only when a block needs a bitmap: fewer
/// registers in the step loop).
struct RayWalk {
  GainWalk walk;
  uint64_t occupied_word, free_word;
  unsigned long long* seen;  ///< dense: the viewpoint's bitmap; pooled: the block's (or null)
  double gain;               ///< bits counted for viewpoint `vp` and not yet added to gains
  int32_t slot;
  int slice;
  int entry;
  uint32_t vp;
  int32_t lo[3], dims[3];  ///< dense: the viewpoint's box (cells)
};

/// Starts ray `ray` (index in the round: viewpoint = ray / rays_per_viewpoint) in `r`,
/// keeping `r.gain` when the viewpoint is the one it counts for; else adds that gain first.
template <bool kPooled>
__device__ void startRay(const GainWalkArgs& a, uint64_t ray, RayWalk& r) {
  // 32-bit: a round has fewer than 2^32 rays (viewpointGainsOnDevice splits rounds so).
  const uint32_t vp = static_cast<uint32_t>(ray) / a.rays_per_viewpoint;
  const uint32_t i = static_cast<uint32_t>(ray) - vp * a.rays_per_viewpoint;
  if (vp != r.vp) {
    if (r.gain != 0.0) atomicAdd(&a.gains[r.vp], r.gain);
    r.gain = 0.0;
    r.vp = vp;
  }
  double dir[3];
  yawRotate(a.cos_yaw[vp], a.sin_yaw[vp], a.rays + 3 * i, dir);
  r.walk = GainWalk::along(a.origins_v + 3 * vp, dir, a.length_v);
  r.entry = kUnknownBlock;
  r.slot = kNoViewSlot;
  r.slice = -1;
  r.occupied_word = r.free_word = 0;
  r.seen = nullptr;
  if (!kPooled) {
    for (int d = 0; d < 3; ++d) {
      r.lo[d] = a.box_lo[3 * vp + d];
      r.dims[d] = a.box_dims[3 * vp + d];
    }
    r.seen = a.seen + a.seen_offset[vp];
  }
}

/// The pool bitmap of block `b` for viewpoint `vp`: taken from the pool and cleared by the
/// first lane that asks (a compare-and-swap on the directory entry from kPoolEmpty to
/// kPoolBusy; every other lane waits while the entry reads kPoolBusy, whichever load saw it),
/// nullptr outside the viewpoint's box (no cell of it is counted, as the plain kernel's box
/// check) or when the pool is full (the viewpoint is flagged, its gain computed again).
/// Memory order: the taker clears the bitmap, then publishes its index with a release store
/// (a fence: the zeros reach L2 first); the others read the entry relaxed (an acquire load at
/// device scope would invalidate the SM's L1, where the masks are read) and touch the bitmap
/// only by atomics, which run at L2 and cannot issue before the index they address is read:
/// the CUDA guide's threadfence pattern (writer fence, reader without one).
template <bool kDeferred>
__device__ unsigned long long* poolBitmap(const GainWalkArgs& a, uint32_t vp, const BlockKey& b) {
  const PoolDirectory dir = PoolDirectory::over(a.box_lo + 3 * vp, a.box_dims + 3 * vp);
  const int64_t at = dir.indexOf(b);
  if (at < 0) return nullptr;
  ::cuda::atomic_ref<uint32_t, ::cuda::thread_scope_device> entry(
      a.directory[__ldg(&a.directory_offset[vp]) + uint64_t(at)]);
  uint32_t v = entry.load(::cuda::memory_order_relaxed);
  if (v == kPoolEmpty) {
    uint32_t expected = kPoolEmpty;
    if (entry.compare_exchange_strong(expected, kPoolBusy, ::cuda::memory_order_relaxed)) {
      v = poolEntryOf(atomicAdd(a.pool_taken, 1u), a.pool_blocks);
      const int64_t taken = poolBitmapOf(v);
      if (taken >= 0) {
        ulonglong2* bits = reinterpret_cast<ulonglong2*>(a.pool + 8 * uint64_t(taken));
        for (int w = 0; w < 4; ++w) bits[w] = make_ulonglong2(0, 0);
        if (kDeferred) a.pool_owner[taken] = PoolOwner{vp, b.x, b.y, b.z};
      }
      entry.store(v, ::cuda::memory_order_release);  // the cleared bitmap before its index
    } else {
      v = expected;  // the entry as the failed exchange read it
    }
  }
  // Another lane is taking the bitmap (seen by the first load or by the failed exchange):
  // wait for its index. (Issue 34: a lane whose first load saw kPoolBusy used it as an index.)
  while (v == kPoolBusy) {
    __nanosleep(32);
    v = entry.load(::cuda::memory_order_relaxed);
  }
  const int64_t index = poolBitmapOf(v);
  if (index < 0) {  // kPoolOverflow
    a.overflow[vp] = 1;
    return nullptr;
  }
  return a.pool + 8 * uint64_t(index);
}

/// `*word |= mask` at L2 without returning the old value (a reduction: the lane does not wait).
__device__ void orBits(unsigned long long* word, unsigned long long mask) {
  asm volatile("red.global.or.b64 [%0], %1;" ::"l"(word), "l"(mask) : "memory");
}

/// One cell of the ray (the plain kernel's loop body): counts it when it is unknown and first
/// seen by the viewpoint (kDeferred: only sets its seen bit, without waiting for the old
/// value), then steps on. False when the ray has ended (an occupied cell, or the end cell
/// visited).
template <bool kPooled, bool kDeferred = false>
__device__ bool stepRay(const GainWalkArgs& a, RayWalk& r) {
  const VoxelKey k = r.walk.cell();
  if (r.entry != kSameBlock) {
    r.slot = gainSlot(a, blockKeyOf(k));
    r.slice = -1;
    if (kPooled) r.seen = nullptr;
  }
  const int c = cellIndexOf(k);
  if ((c >> 6) != r.slice) {
    r.slice = c >> 6;
    r.occupied_word = r.slot == kNoViewSlot ? 0 : a.view.masks[r.slot].occupied[r.slice];
    r.free_word = r.slot == kNoViewSlot ? 0 : a.view.masks[r.slot].free[r.slice];
  }
  const uint64_t cell_bit = uint64_t{1} << (c & 63);
  if (r.occupied_word & cell_bit) return false;
  if (!(r.free_word & cell_bit)) {  // unknown
    unsigned long long* word = nullptr;
    unsigned long long mask = 0;
    if (kPooled) {
      if (r.seen == nullptr) r.seen = poolBitmap<kDeferred>(a, r.vp, blockKeyOf(k));
      if (r.seen) {
        word = r.seen + (c >> 6);
        mask = cell_bit;
      }
    } else {
      const int64_t lx = k.x - r.lo[0], ly = k.y - r.lo[1], lz = k.z - r.lo[2];
      if (lx >= 0 && ly >= 0 && lz >= 0 && lx < r.dims[0] && ly < r.dims[1] && lz < r.dims[2]) {
        const uint64_t bit = uint64_t((lz * r.dims[1] + ly) * r.dims[0] + lx);
        word = r.seen + (bit >> 6);
        mask = 1ULL << (bit & 63);
      }
    }
    if (kDeferred) {
      if (word) orBits(word, mask);
    } else if (word && !(atomicOr(word, mask) & mask))
      r.gain +=
          cellGainBits(a.model, r.slot == kNoViewSlot ? nullptr : &a.view.cells[r.slot].cells[c]);
  }
  if (r.walk.done()) return false;
  r.entry = r.walk.next();
  return true;
}

/// One thread a ray (sized, pooled, pooled-deferred): the plain kernel's shape.
template <bool kPooled, bool kDeferred>
__global__ void __launch_bounds__(kWalkThreads, kWalkBlocksPerSm) gainWalkKernel(GainWalkArgs a) {
  const uint64_t idx = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  const uint64_t total = uint64_t(a.viewpoints) * a.rays_per_viewpoint;
  RayWalk r;
  r.gain = 0.0;
  r.vp = 0;
  if (idx < total) {
    startRay<kPooled>(a, idx, r);
    while (stepRay<kPooled, kDeferred>(a, r)) {
    }
  }
  // Rays of one viewpoint are consecutive: sum within the warp where all lanes share it.
  const uint32_t first_vp = __shfl_sync(kFullWarp, r.vp, 0);
  double gain = r.gain;
  if (__all_sync(kFullWarp, r.vp == first_vp)) {
    for (int offset = 16; offset > 0; offset /= 2)
      gain += __shfl_down_sync(kFullWarp, gain, offset);
    if ((threadIdx.x & 31) == 0 && gain != 0.0) atomicAdd(&a.gains[first_vp], gain);
  } else if (idx < total && gain != 0.0) {
    atomicAdd(&a.gains[r.vp], gain);
  }
}

/// Persistent threads (queued, pooled-queued): every launched thread starts with one ray; a
/// lane whose ray ends waits, and once `refill_lanes` lanes of the warp wait, the warp takes
/// that many next rays from the queue with one atomic. A lane adds its gain to the viewpoint's
/// when it moves to another viewpoint's ray, and at the end.
template <bool kPooled, bool kDeferred>
__global__ void __launch_bounds__(kWalkThreads, kWalkBlocksPerSm) gainQueueKernel(GainWalkArgs a) {
  const uint64_t total = uint64_t(a.viewpoints) * a.rays_per_viewpoint;
  const uint64_t launched = uint64_t(gridDim.x) * blockDim.x;
  const uint64_t first = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  const unsigned lane = threadIdx.x & 31;
  RayWalk r;
  r.gain = 0.0;
  r.vp = 0;
  bool live = first < total;
  if (live) startRay<kPooled>(a, first, r);
  bool drained = launched >= total;  // the same in every lane of the warp
  for (;;) {
    for (int s = 0; s < kQueueBurst && live; ++s) live = stepRay<kPooled, kDeferred>(a, r);
    const unsigned live_lanes = __ballot_sync(kFullWarp, live);
    if (drained) {
      if (live_lanes == 0) break;
      continue;
    }
    const unsigned idle = ~live_lanes;
    const int n_idle = __popc(idle);
    if (n_idle < a.refill_lanes) continue;
    unsigned long long base = 0;
    if (lane == 0) base = atomicAdd(a.queue, static_cast<unsigned long long>(n_idle));
    base = __shfl_sync(kFullWarp, base, 0) + launched;
    if (base + n_idle >= total) drained = true;
    if (!live) {
      const uint64_t ray = base + __popc(idle & ((1u << lane) - 1u));
      if (ray < total) {
        startRay<kPooled>(a, ray, r);
        live = true;
      }
    }
  }
  if (r.gain != 0.0) atomicAdd(&a.gains[r.vp], r.gain);
}

constexpr int kSumThreads = 256;

/// The deferred kernel's second pass: the entropy of every cell set in the round's taken pool
/// bitmaps (all unknown cells: 1 bit where the block is missing or the cell never observed,
/// H(p) in the unknown band), added to the bitmap's viewpoint. Eight lanes a bitmap, a word
/// each; one atomic a bitmap.
__global__ void __launch_bounds__(kSumThreads) poolGainSumKernel(GainWalkArgs a) {
  const uint64_t words = 8 * uint64_t(min(*a.pool_taken, a.pool_blocks));
  const uint64_t stride = uint64_t(gridDim.x) * blockDim.x;
  // The loop's bounds are the same for every lane of a block (the shuffles need whole warps).
  for (uint64_t base = uint64_t(blockIdx.x) * blockDim.x; base < words; base += stride) {
    const uint64_t t = base + threadIdx.x;
    double sum = 0.0;
    uint32_t vp = 0;
    if (t < words) {
      const PoolOwner o = a.pool_owner[t >> 3];
      vp = o.vp;
      const int w = static_cast<int>(t & 7);
      unsigned long long bits = a.pool[t];
      if (bits) {
        const int32_t slot = gainSlot(a, BlockKey{o.x, o.y, o.z});
        if (slot == kNoViewSlot) {
          sum = __popcll(bits);
        } else {
          while (bits) {
            const int b = __ffsll(static_cast<long long>(bits)) - 1;
            bits &= bits - 1;
            sum += cellGainBits(a.model, &a.view.cells[slot].cells[64 * w + b]);
          }
        }
      }
    }
    sum += __shfl_xor_sync(kFullWarp, sum, 1);
    sum += __shfl_xor_sync(kFullWarp, sum, 2);
    sum += __shfl_xor_sync(kFullWarp, sum, 4);
    if (t < words && (t & 7) == 0 && sum != 0.0) atomicAdd(&a.gains[vp], sum);
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

void launchGainWalk(const GainWalkArgs& args, bool pooled, bool queued, bool deferred,
                    cudaStream_t stream) {
  const uint64_t total = uint64_t(args.viewpoints) * args.rays_per_viewpoint;
  if (total == 0) return;
  uint64_t grid = (total + kWalkThreads - 1) / kWalkThreads;
  int device = 0, sms = 0;
  FRAGG_CUDA_CHECK(cudaGetDevice(&device));
  FRAGG_CUDA_CHECK(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device));
  sms = std::max(1, sms);
  // deferred implies pooled.
  using Kernel = void (*)(GainWalkArgs);
  const Kernel kernel = queued ? (deferred ? gainQueueKernel<true, true>
                                  : pooled ? gainQueueKernel<true, false>
                                           : gainQueueKernel<false, false>)
                               : (deferred ? gainWalkKernel<true, true>
                                  : pooled ? gainWalkKernel<true, false>
                                           : gainWalkKernel<false, false>);
  if (queued) {
    // As many blocks as the device runs at once (no more: a later block would start only when
    // an earlier one has drained the queue).
    int per_sm = 0;
    FRAGG_CUDA_CHECK(
        cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, kernel, kWalkThreads, 0));
    grid = std::min<uint64_t>(grid, uint64_t(sms) * uint64_t(std::max(1, per_sm)));
  }
  kernel<<<static_cast<unsigned>(grid), kWalkThreads, 0, stream>>>(args);
  FRAGG_CUDA_CHECK(cudaGetLastError());
  if (deferred) {
    poolGainSumKernel<<<static_cast<unsigned>(4 * sms), kSumThreads, 0, stream>>>(args);
    FRAGG_CUDA_CHECK(cudaGetLastError());
  }
}

}  // namespace fragg::cuda
