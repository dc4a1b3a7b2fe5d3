// The ray pass: one thread a ray, the same traversal as the CPU backend (raycast.h), marking
// FREE / HIT bits in the scratch of the block's slot. Blocks without a slot get one from the
// free stack the first time a ray enters them.
#include "cuda_check.h"
#include "fragg_map/raycast.h"
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

/// The slot of block `b` for this scan, or -1 when the ray must skip its cells (host-only
/// block not uploaded yet, pool full): the host then fixes that and runs the pass again.
__device__ int32_t resolveSlot(const RaycastArgs& a, const BlockKey& b) {
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
      if (pos < 0) {
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
      slot = resolveSlot(a, blockKeyOf(v));
      have_block = true;
      // Written by earlier kernels only (apply, upload, the clear on release): a new slot
      // taken in this pass comes off the free stack with 0.
      saturated = slot >= 0 && a.skip_saturated && !a.remove && a.slots.free_saturated[slot] != 0;
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

template <bool kReadOnly, bool kBresenham>
__global__ void __launch_bounds__(kThreads) raycastKernel(RaycastArgs a) {
  __shared__ unsigned long long filter[kFilterEntries];
  for (int k = threadIdx.x; k < kFilterEntries; k += blockDim.x) filter[k] = ~0ull << 32;
  __syncthreads();
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  unsigned long long visits = 0;
  if (i < a.num_rays) {
    RayEnd e;
    if (kReadOnly) {
      const float4 raw = __ldg(reinterpret_cast<const float4*>(a.rays) + i);
      e.end_v[0] = raw.x;
      e.end_v[1] = raw.y;
      e.end_v[2] = raw.z;
      e.hit = __float_as_uint(raw.w);
    } else {
      e = a.rays[i];
    }
    const RayVox ray{a.ref,
                     {a.start_v[0], a.start_v[1], a.start_v[2]},
                     {e.end_v[0], e.end_v[1], e.end_v[2]},
                     e.hit != 0,
                     marginOfHitCode(e.hit)};
    DeviceMarker mark{a, MarkFilter{filter}};
    visits = kBresenham ? traverseBresenham(ray, mark) : traverseDda(ray, mark);
    mark.flush();
  }
  visits = warpSum(visits);
  if ((threadIdx.x & 31) == 0 && visits) atomicAdd(&a.counters->visits, visits);
}
}  // namespace

void launchRaycast(const RaycastArgs& args, RayCast mode, bool readonly_loads,
                   cudaStream_t stream) {
  if (args.num_rays == 0) return;
  const unsigned grid = blocksFor(args.num_rays, kThreads);
  const bool bresenham = mode == RayCast::kBresenham;
  if (readonly_loads && !bresenham)
    raycastKernel<true, false><<<grid, kThreads, 0, stream>>>(args);
  else if (readonly_loads)
    raycastKernel<true, true><<<grid, kThreads, 0, stream>>>(args);
  else if (!bresenham)
    raycastKernel<false, false><<<grid, kThreads, 0, stream>>>(args);
  else
    raycastKernel<false, true><<<grid, kThreads, 0, stream>>>(args);
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
