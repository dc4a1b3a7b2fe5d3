// The ray pass: one thread a ray, or a CTA's rays cut into pieces that its threads share; the
// same traversal as the CPU backend (raycast.h), marking FREE / HIT bits in the scratch of the
// block's slot. Blocks without a slot get one from the free stack the first time a ray enters
// them.
#include "cuda_check.h"
#include "fragg_map/raycast.h"
#include "fragg_map/raycast_octomap.h"
#include "kernels.h"
#include "warp_reduce.cuh"

namespace fragg::cuda {

namespace {
constexpr unsigned kThreads = 128;

__device__ __forceinline__ int32_t loadEntry(const int32_t* e) {
  return *reinterpret_cast<const volatile int32_t*>(e);
}

/// Per-CTA filter of scratch words this CTA has already OR-ed a bit into: rays start in the
/// same cell and share the cells near the sensor, and thousands of atomics on one word would
/// serialise in L2. An entry is (tag = slot * 32 + word) << 32 | bits; a bit is set in it only
/// after its global atomicOr was issued, so skipping on a set bit never loses a mark.
constexpr int kFilterEntries = 512;
struct MarkFilter {
  unsigned long long* entries;  // shared memory
};

/// The window entry of block `b` for this scan: its slot with kWindowSaturatedBit, or -1
/// when the ray must skip its cells (host-only block not uploaded yet, pool full): the host
/// then fixes that and runs the pass again.
__device__ int32_t resolveEntry(const RaycastArgs& a, const BlockKey& b) {
  const int64_t idx = a.window.indexOf(b);
  if (idx < 0) {
    atomicAdd(&a.counters->outside_window, 1u);
    return -1;
  }
  int32_t* entry = a.window.entries + idx;
  // A slot, once in the window, never changes during the pass: a cached (maybe stale) read
  // that shows one is right; anything else is read again coherently.
  int32_t v = *entry;
  if (v < 0) v = loadEntry(entry);
  for (;;) {
    if (v >= 0) break;
    if (v == kWindowEmpty) {
      if (a.remove) return -1;
      const int32_t prev = atomicCAS(entry, kWindowEmpty, kWindowBusy);
      if (prev != kWindowEmpty) {
        v = prev;
        continue;
      }
      const int32_t pos = atomicSub(&a.counters->free_top, 1) - 1;
      if (pos < a.free_floor) {
        atomicAdd(&a.counters->overflow, 1u);
        atomicExch(entry, kWindowOverflow);
        return -1;
      }
      const int32_t slot = a.slots.free_stack[pos];
      a.slots.keys[slot] = b;
      a.slots.fresh[slot] = 1;
      a.slots.resident[slot] = 1;
      // No fence: rays that read the slot from the entry only touch its scratch; the keys
      // and flags written above are read by later kernels.
      atomicExch(entry, slot);
      v = slot;
      break;
    }
    if (v == kWindowBusy) {  // another ray is allocating it: wait (independent scheduling)
      v = loadEntry(entry);
      continue;
    }
    if (v == kWindowHostOnly &&
        atomicCAS(entry, kWindowHostOnly, kWindowMissed) == kWindowHostOnly) {
      const uint32_t k = atomicAdd(&a.counters->misses, 1u);
      if (k < a.miss_capacity) a.miss_list[k] = static_cast<int32_t>(idx);
    }
    return -1;  // host-only, missed, overflow
  }
  return v;
}

struct DeviceMarker {
  const RaycastArgs& a;
  MarkFilter filter;
  int32_t slot = -1;
  bool have_block = false;
  bool saturated = false;   ///< the block's misses change nothing (inserting only)
  bool skip_block = false;  ///< the last free cell was in such a block
  /// Marks of this ray not issued yet: the bits of one scratch word (tag = slot * 32 + word
  /// index, free words then hit words). Consecutive cells of a ray often share a word (8
  /// along x, 4 rows along y), so they cost one filter look-up and one atomic together.
  uint32_t pending_tag = 0;
  uint32_t pending_bits = 0;

  /// Lets traverseDda walk past the rest of a saturated block (raycast.h).
  __device__ bool skippingBlock() const { return skip_block; }

  /// Issues the pending marks (at a new word and at the end of the ray).
  __device__ void flush() {
    if (pending_bits == 0) return;
    const uint32_t tag = pending_tag, bits = pending_bits;
    pending_bits = 0;
    unsigned long long* f = filter.entries + (((tag * 2654435761u) >> 23) & (kFilterEntries - 1));
    const unsigned long long seen = *reinterpret_cast<volatile unsigned long long*>(f);
    const bool same = (seen >> 32) == tag;
    if (same && (static_cast<uint32_t>(seen) & bits) == bits) return;
    uint32_t* word = reinterpret_cast<uint32_t*>(&a.slots.scratch[tag >> 5]) + (tag & 31);
    atomicOr(word, bits);  // result unused: a fire-and-forget reduction
    const unsigned long long want =
        same ? (seen | bits) : ((static_cast<unsigned long long>(tag) << 32) | bits);
    // Every bit in `seen` was issued by someone, so whichever exchange wins, a set bit still
    // means an issued atomic; a lost bit only costs a later atomic.
    atomicExch(f, want);
  }

  __device__ void operator()(const VoxelKey& v, bool hit, int entry) {
    if (entry != kSameBlock || !have_block) {
      const int32_t e = resolveEntry(a, blockKeyOf(v));
      have_block = true;
      slot = e < 0 ? -1 : (e & kWindowSlotMask);
      // The flag as the window fill copied it; a slot taken in this pass comes off the free
      // stack with 0 and its entry has no flag.
      saturated = e >= 0 && a.skip_saturated && !a.remove && (e & kWindowSaturatedBit) != 0;
    }
    skip_block = saturated && !hit;
    if (slot < 0 || skip_block) return;
    const int cell = cellIndexOf(v);
    const uint32_t word_index = (hit ? kScratchWords : 0) + (cell >> 5);
    const uint32_t tag = static_cast<uint32_t>(slot) * 32u + word_index;
    if (tag != pending_tag) {
      flush();
      pending_tag = tag;
    }
    pending_bits |= 1u << (cell & 31);
    if (!a.coalesce) flush();
  }
};
static_assert(sizeof(SlotScratch) == 32 * sizeof(uint32_t), "free words, then hit words");

/// A slot is touched when its scratch has a mark: one warp reads a slot's 128 B of scratch.
/// Touched slots are listed for the apply kernel and stamped, so that an eviction between a
/// failed pass and its retry never takes one.
__global__ void compactTouchedKernel(SlotArrays s, uint32_t scan, ScanCounters* c) {
  const int64_t warp = (int64_t(blockIdx.x) * blockDim.x + threadIdx.x) / 32;
  const unsigned lane = threadIdx.x & 31;
  if (warp >= s.capacity) return;
  const int32_t slot = static_cast<int32_t>(warp);
  const uint32_t word = reinterpret_cast<const uint32_t*>(&s.scratch[slot])[lane];
  if (!__any_sync(kFullMask, word != 0u)) return;
  if (lane == 0) {
    s.touched_list[atomicAdd(&c->touched, 1u)] = slot;
    s.last_used[slot] = scan;
  }
}

static_assert(sizeof(RayEnd) == sizeof(float4), "a ray end is read as one float4");

template <bool kReadOnly>
__device__ float4 loadRay(const RaycastArgs& a, uint32_t i) {
  const float4* rays = reinterpret_cast<const float4*>(a.rays);
  return kReadOnly ? __ldg(rays + i) : rays[i];
}

__device__ RayVox rayOf(const RaycastArgs& a, const float4& end) {
  const uint32_t hit = __float_as_uint(end.w);
  return RayVox{a.ref,
                {a.start_v[0], a.start_v[1], a.start_v[2]},
                {end.x, end.y, end.z},
                isHitCode(hit),
                marginOfHitCode(hit),
                hit == kFreeEndCode};
}

/// The same ray for traverseOctomapKeys (RayCast::kOctomap: `end` in float metres).
__device__ RayMetres rayMetresOf(const RaycastArgs& a, const float4& end) {
  const uint32_t hit = __float_as_uint(end.w);
  return RayMetres{{a.origin_m[0], a.origin_m[1], a.origin_m[2]},
                   {end.x, end.y, end.z},
                   a.resolution_m,
                   a.inv_res,
                   isHitCode(hit),
                   marginOfHitCode(hit),
                   hit == kFreeEndCode};
}

__device__ void clearFilter(unsigned long long* filter) {
  for (int k = threadIdx.x; k < kFilterEntries; k += blockDim.x) filter[k] = ~0ull << 32;
}

__device__ void addVisits(const RaycastArgs& a, unsigned long long visits) {
  visits = warpSum(visits);
  if ((threadIdx.x & 31) == 0 && visits) atomicAdd(&a.counters->visits, visits);
}

/// One thread a ray.
template <bool kReadOnly, RayCast kMode>
__global__ void __launch_bounds__(kThreads) raycastKernel(RaycastArgs a) {
  __shared__ unsigned long long filter[kFilterEntries];
  clearFilter(filter);
  __syncthreads();
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  unsigned long long visits = 0;
  if (i < a.num_rays) {
    const float4 end = loadRay<kReadOnly>(a, i);
    DeviceMarker mark{a, MarkFilter{filter}};
    if constexpr (kMode == RayCast::kOctomap) {
      const RayMetres ray = rayMetresOf(a, end);
      visits = traverseOctomapKeys(ray, mark);
    } else {
      const RayVox ray = rayOf(a, end);
      visits = kMode == RayCast::kBresenham ? traverseBresenham(ray, mark) : traverseDda(ray, mark);
    }
    mark.flush();
  }
  addVisits(a, visits);
}

/// A CTA's rays cut into pieces (DdaPiece) of `a.piece_steps` steps of their major axis, so
/// that its threads share the walks evenly instead of each warp waiting for its longest ray.
/// At most kMaxPieces a ray (a longer ray gets longer pieces).
constexpr int kMaxPieces = 64;
constexpr int kWarps = kThreads / 32;

/// The CTA's work list, piece by piece: every ray's first piece, then the second pieces of the
/// rays that have one, and so on, rays in order within each layer. A warp's consecutive items
/// are then the same piece of neighbouring rays (nearby cells: the mark filter and L1 keep
/// their locality), and the threads stride through the list, so none waits for a long ray.
struct PieceList {
  uint8_t ray[kThreads * kMaxPieces];  ///< the CTA's ray of each item
  uint16_t layer_start[kMaxPieces + 1];
  uint16_t warp_count[kWarps][kMaxPieces];  ///< a warp's rays with a piece in each layer
};

/// Fills `list` from each thread's piece count (0 without a ray). Every thread of the CTA
/// calls it; warp_count must be zero and visible to all threads on entry.
__device__ void buildPieceList(PieceList& list, int pieces) {
  const unsigned lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
  for (int k = 0; __any_sync(kFullMask, pieces > k); ++k) {
    const unsigned have = __ballot_sync(kFullMask, pieces > k);
    if (lane == 0) list.warp_count[warp][k] = static_cast<uint16_t>(__popc(have));
  }
  __syncthreads();
  if (warp == 0) {  // layer sizes, two layers a lane, then a warp-wide scan
    unsigned size[2];
    for (int h = 0; h < 2; ++h) {
      size[h] = 0;
      for (int w = 0; w < kWarps; ++w) size[h] += list.warp_count[w][2 * lane + h];
    }
    const unsigned pair = size[0] + size[1];
    unsigned sum = pair;
    for (int d = 1; d < 32; d *= 2) {
      const unsigned up = __shfl_up_sync(kFullMask, sum, d);
      if (lane >= d) sum += up;
    }
    list.layer_start[2 * lane] = static_cast<uint16_t>(sum - pair);
    list.layer_start[2 * lane + 1] = static_cast<uint16_t>(sum - pair + size[0]);
    if (lane == 31) list.layer_start[kMaxPieces] = static_cast<uint16_t>(sum);
  }
  __syncthreads();
  const unsigned below = (1u << lane) - 1u;
  for (int k = 0; __any_sync(kFullMask, pieces > k); ++k) {
    const unsigned have = __ballot_sync(kFullMask, pieces > k);
    if (pieces <= k) continue;
    unsigned pos = list.layer_start[k] + __popc(have & below);
    for (int w = 0; w < static_cast<int>(warp); ++w) pos += list.warp_count[w][k];
    list.ray[pos] = static_cast<uint8_t>(threadIdx.x);
  }
  __syncthreads();
}

template <bool kReadOnly>
__global__ void __launch_bounds__(kThreads) raycastPiecesKernel(RaycastArgs a) {
  static_assert(kThreads <= 256 && kThreads * kMaxPieces <= 65535, "item indices fit");
  __shared__ unsigned long long filter[kFilterEntries];
  __shared__ float4 ray_end[kThreads];
  __shared__ int piece_len[kThreads];  ///< major-axis steps a piece of each ray
  __shared__ PieceList list;
  clearFilter(filter);
  for (int k = threadIdx.x; k < kWarps * kMaxPieces; k += blockDim.x)
    (&list.warp_count[0][0])[k] = 0;
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  int pieces = 0;
  if (i < a.num_rays) {
    const float4 end = loadRay<kReadOnly>(a, i);
    ray_end[threadIdx.x] = end;
    const int major = ddaMajorSteps(rayOf(a, end));
    const int per_piece = a.piece_steps;
    const int len =
        major > per_piece * kMaxPieces ? (major + kMaxPieces - 1) / kMaxPieces : per_piece;
    piece_len[threadIdx.x] = len;
    pieces = major > 0 ? (major + len - 1) / len : 1;
  }
  __syncthreads();
  buildPieceList(list, pieces);
  const int items = list.layer_start[kMaxPieces];
  unsigned long long visits = 0;
  int k = 0;
  for (int item = threadIdx.x; item < items; item += kThreads) {
    while (item >= list.layer_start[k + 1]) ++k;
    const int r = list.ray[item];
    const int len = piece_len[r];
    DeviceMarker mark{a, MarkFilter{filter}};
    visits += traverseDdaPiece(rayOf(a, ray_end[r]), DdaPiece{k * len, (k + 1) * len}, mark);
    mark.flush();
  }
  addVisits(a, visits);
}
}  // namespace

void launchRaycast(const RaycastArgs& args, RayCast mode, bool readonly_loads,
                   cudaStream_t stream) {
  if (args.num_rays == 0) return;
  const unsigned grid = blocksFor(args.num_rays, kThreads);
  if (mode == RayCast::kDda && args.piece_steps > 0) {
    if (readonly_loads)
      raycastPiecesKernel<true><<<grid, kThreads, 0, stream>>>(args);
    else
      raycastPiecesKernel<false><<<grid, kThreads, 0, stream>>>(args);
  } else if (mode == RayCast::kOctomap) {  // its walk accumulates: one thread a ray
    if (readonly_loads)
      raycastKernel<true, RayCast::kOctomap><<<grid, kThreads, 0, stream>>>(args);
    else
      raycastKernel<false, RayCast::kOctomap><<<grid, kThreads, 0, stream>>>(args);
  } else if (mode == RayCast::kBresenham) {
    if (readonly_loads)
      raycastKernel<true, RayCast::kBresenham><<<grid, kThreads, 0, stream>>>(args);
    else
      raycastKernel<false, RayCast::kBresenham><<<grid, kThreads, 0, stream>>>(args);
  } else if (readonly_loads) {
    raycastKernel<true, RayCast::kDda><<<grid, kThreads, 0, stream>>>(args);
  } else {
    raycastKernel<false, RayCast::kDda><<<grid, kThreads, 0, stream>>>(args);
  }
  FRAGG_CUDA_CHECK_LAUNCH("raycastKernel");
}

void launchCompactTouched(const SlotArrays& slots, uint32_t scan, ScanCounters* counters,
                          cudaStream_t stream) {
  if (slots.capacity == 0) return;
  compactTouchedKernel<<<blocksFor(uint64_t(slots.capacity) * 32, 256), 256, 0, stream>>>(
      slots, scan, counters);
  FRAGG_CUDA_CHECK_LAUNCH("compactTouchedKernel");
}

}  // namespace fragg::cuda
