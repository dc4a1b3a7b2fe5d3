// MapParams::dynamic on the device (DESIGN §12): the classification of a scan's hits before the
// ray pass and the void cells of its touched slots between the ray pass and the apply, with the
// CPU's own tests (fragg_map/internal/dynamic_eval.h) read through the window. A block the
// window has on the host only is recorded as a miss (as a ray records one): the host uploads it
// and the kernel runs again, so every block read is resident.
#include "cuda_check.h"
#include "fragg_map/internal/dynamic_eval.h"
#include "kernels.h"
#include "warp_reduce.cuh"

namespace fragg::cuda {

namespace {
constexpr unsigned kThreads = 128;

/// What a block of the window was before this scan.
enum class Before { kResident, kNone, kIncomplete };

/// Block lookups through the window for the dynamic kernels.
struct WindowBlocks {
  const DynamicPassArgs& a;
  bool incomplete = false;  ///< a block was host-only: the result is void, the pass redone

  /// The slot of block `b` (`*slot`), with `*fresh` when a ray of this scan allocated it (then
  /// the block did not exist before the scan: no cells, no masks; its marks are the scan's).
  __device__ Before slotOf(const BlockKey& b, int32_t* slot, bool* fresh) {
    *slot = -1;
    *fresh = false;
    const int64_t idx = a.window.indexOf(b);
    if (idx < 0) {
      atomicAdd(&a.counters->outside_window, 1u);
      incomplete = true;
      return Before::kIncomplete;
    }
    int32_t* entry = a.window.entries + idx;
    const int32_t v = *reinterpret_cast<const volatile int32_t*>(entry);
    if (v >= 0) {
      *slot = v & kWindowSlotMask;
      *fresh = a.slots.fresh[*slot] != 0;
      // Read for this scan: not evicted to make room for another block it needs.
      if (!*fresh) a.slots.last_used[*slot] = a.scan;
      return Before::kResident;
    }
    if (v == kWindowHostOnly &&
        atomicCAS(entry, kWindowHostOnly, kWindowMissed) == kWindowHostOnly) {
      const uint32_t k = atomicAdd(&a.counters->misses, 1u);
      atomicAdd(&a.counters->void_misses, 1u);  // not the rays': their marks are complete
      if (k < a.miss_capacity) a.miss_list[k] = static_cast<int32_t>(idx);
    }
    if (v == kWindowHostOnly || v == kWindowMissed) {
      incomplete = true;
      return Before::kIncomplete;
    }
    return Before::kNone;  // empty, or a slot the pool could not give (the pass is redone)
  }
};

/// Cells as they were before the scan (dynamic_eval's Reader): null where no block was.
struct WindowCellReader {
  WindowBlocks& blocks;
  BlockKey key{0, 0, 0};
  const Block* block = nullptr;
  bool valid = false;

  __device__ const Cell* find(const VoxelKey& v) {
    const BlockKey b = blockKeyOf(v);
    if (!valid || b != key) {
      key = b;
      valid = true;
      int32_t slot;
      bool fresh;
      const Before was = blocks.slotOf(b, &slot, &fresh);
      block = was == Before::kResident && !fresh ? &blocks.a.slots.cells[slot] : nullptr;
    }
    return block ? &block->cells[cellIndexOf(v)] : nullptr;
  }
};

/// One thread a ray: flags[i] = 1 when ray i's hit is dynamic (dynamic_eval::dynamicAt).
__global__ void __launch_bounds__(kThreads)
    classifyKernel(DynamicPassArgs a, const RayEnd* __restrict__ rays, uint32_t num_rays,
                   uint8_t* __restrict__ flags) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= num_rays) return;
  const RayEnd ray = rays[i];
  bool dynamic = false;
  if (isHitCode(ray.hit)) {
    const VoxelKey end{a.ref.x + rayEndCell(ray, 0, a.octomap_keys, a.inv_res, a.ref.x),
                       a.ref.y + rayEndCell(ray, 1, a.octomap_keys, a.inv_res, a.ref.y),
                       a.ref.z + rayEndCell(ray, 2, a.octomap_keys, a.inv_res, a.ref.z)};
    WindowBlocks blocks{a};
    WindowCellReader cells{blocks};
    dynamic = dynamic_eval::dynamicAt(end, cells, a.rule) && !blocks.incomplete;
  }
  flags[i] = dynamic ? 1 : 0;
}

/// The flagged rays become free-only (hit = 0) and their points are listed.
__global__ void dropDynamicKernel(RayEnd* rays, uint32_t num_rays, const uint8_t* flags,
                                  const uint32_t* ray_points, uint32_t* points, ScanCounters* c) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= num_rays || flags[i] == 0) return;
  rays[i].hit = 0u;
  points[atomicAdd(&c->dynamic, 1u)] = ray_points[i];
}

/// The seen-free mask of block `b` (dynamic_eval::seenFreeMask); false when it is host-only.
__device__ bool seenFree(WindowBlocks& blocks, const BlockKey& b, uint64_t* out) {
  int32_t slot;
  bool fresh;
  const Before was = blocks.slotOf(b, &slot, &fresh);
  if (was == Before::kIncomplete) return false;
  const uint64_t *free_marks = nullptr, *hit_marks = nullptr, *occupied = nullptr, *free = nullptr;
  if (was == Before::kResident) {
    const SlotScratch& s = blocks.a.slots.scratch[slot];
    free_marks = reinterpret_cast<const uint64_t*>(s.free);
    hit_marks = reinterpret_cast<const uint64_t*>(s.hit);
    if (!fresh) {
      occupied = blocks.a.slots.masks[slot].occupied;
      free = blocks.a.slots.masks[slot].free;
    }
  }
  dynamic_eval::seenFreeMask(free_marks, hit_marks, occupied, free, out);
  return true;
}

/// One thread a touched slot: its void cells (8 words at void_bits[slot * 8]), the CPU's
/// passThroughResets / surroundedCells over the window's blocks.
__global__ void __launch_bounds__(kThreads)
    voidCellsKernel(DynamicPassArgs a, uint64_t* void_bits) {
  using dynamic_eval::kWords;
  const ScanCounters* c = a.counters;
  if (c->overflow != 0) return;  // the pass is redone: the slots' marks are not complete
  const uint32_t j = blockIdx.x * blockDim.x + threadIdx.x;
  if (j >= c->touched) return;
  const int32_t slot = a.slots.touched_list[j];
  const SlotScratch& scratch = a.slots.scratch[slot];
  const uint64_t* free_marks = reinterpret_cast<const uint64_t*>(scratch.free);
  const uint64_t* hit_marks = reinterpret_cast<const uint64_t*>(scratch.hit);
  const bool fresh = a.slots.fresh[slot] != 0;
  uint64_t* out = void_bits + int64_t(slot) * kWords;
  uint64_t candidates[kWords];
  uint64_t any = 0;
  for (int w = 0; w < kWords; ++w) {
    candidates[w] = free_marks[w] & ~hit_marks[w];
    if (!a.rule.surround) candidates[w] &= fresh ? 0 : a.slots.masks[slot].occupied[w];
    any |= candidates[w];
  }
  for (int w = 0; w < kWords; ++w) out[w] = 0;
  if (any == 0) return;
  WindowBlocks blocks{a};
  const BlockKey key = a.slots.keys[slot];
  if (!a.rule.surround) {  // kPassThrough: occupied cells passed through, neighbourhood observed
    WindowCellReader cells{blocks};
    for (int w = 0; w < kWords; ++w)
      for (uint64_t bits = candidates[w]; bits != 0; bits &= bits - 1) {
        const int cell = w * 64 + __ffsll(static_cast<long long>(bits)) - 1;
        if (dynamic_eval::observedAround(voxelKeyOf(key, cell), cells, a.rule) &&
            !blocks.incomplete)
          out[w] |= uint64_t{1} << (cell & 63);
      }
    return;
  }
  uint64_t seen[27][kWords];
  const uint64_t* around[27];
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int n = (dz + 1) * 9 + (dy + 1) * 3 + (dx + 1);
        if (!seenFree(blocks, BlockKey{key.x + dx, key.y + dy, key.z + dz}, seen[n])) return;
        around[n] = seen[n];
      }
  dynamic_eval::surroundedMask(around, a.rule.known_radius_cells, candidates, out);
}
}  // namespace

void launchClassifyDynamic(const DynamicPassArgs& args, const RayEnd* rays, uint32_t num_rays,
                           uint8_t* flags, cudaStream_t stream) {
  if (num_rays == 0) return;
  classifyKernel<<<blocksFor(num_rays, kThreads), kThreads, 0, stream>>>(args, rays, num_rays,
                                                                         flags);
  FRAGG_CUDA_CHECK_LAUNCH("classifyKernel");
}

void launchDropDynamic(RayEnd* rays, uint32_t num_rays, const uint8_t* flags,
                       const uint32_t* ray_points, uint32_t* points, ScanCounters* counters,
                       cudaStream_t stream) {
  if (num_rays == 0) return;
  dropDynamicKernel<<<blocksFor(num_rays, kThreads), kThreads, 0, stream>>>(
      rays, num_rays, flags, ray_points, points, counters);
  FRAGG_CUDA_CHECK_LAUNCH("dropDynamicKernel");
}

void launchVoidCells(const DynamicPassArgs& args, uint32_t max_touched, uint64_t* void_bits,
                     cudaStream_t stream) {
  if (max_touched == 0) return;
  voidCellsKernel<<<blocksFor(max_touched, kThreads), kThreads, 0, stream>>>(args, void_bits);
  FRAGG_CUDA_CHECK_LAUNCH("voidCellsKernel");
}

}  // namespace fragg::cuda
