// Launchers of the CUDA backend's kernels (host-callable; definitions in the .cu files).
// Every launcher runs on the given stream and checks the launch.
#pragma once

#include <cuda_runtime.h>

#include "auto_stats_accum.h"
#include "device_types.h"
#include "fragg_map/dynamic_rule.h"
#include "fragg_map/frustum.h"
#include "fragg_map/internal/ray_prep.h"
#include "fragg_map/map_params.h"
#include "fragg_map/occupancy.h"

namespace fragg::cuda {

/// Points (x, y, z float triples, sensor frame) -> compacted rays; counts points by outcome
/// and bounds the rays (ScanCounters::lo_v / hi_v). `free_only`: nullptr, or one flag per
/// point (PointCloud::free_only). `ray_points`: nullptr, or gets each ray's point index.
void launchPrepare(const float* points_S, const uint8_t* free_only, uint32_t n,
                   const RayPrepParams& p, const Frustum& f, RayEnd* rays, uint32_t* ray_points,
                   ScanCounters* counters, cudaStream_t stream);

/// Merges the statistics of the auto sensor model of points (x, y, z float triples, sensor
/// frame) into `out` (AutoStatsAccum::empty() for a fresh gather): the bits of
/// gatherAutoSensorStats() on the host.
void launchAutoSensorStats(const float* points_S, uint32_t n, const SensorAxisTable& axes,
                           AutoStatsAccum* out, cudaStream_t stream);

struct RaycastArgs {
  const RayEnd* rays;
  uint32_t num_rays;
  VoxelKey ref;
  float start_v[3];
  /// RayCast::kOctomap: the sensor origin in float metres and the resolution (the rays end in
  /// float metres, PreparedScan::rayMetres).
  float origin_m[3] = {0.f, 0.f, 0.f};
  double resolution_m = 0.0;
  double inv_res = 0.0;
  Window window;
  SlotArrays slots;
  int32_t* miss_list;  ///< window indices of host-only blocks the rays needed
  uint32_t miss_capacity;
  ScanCounters* counters;
  uint32_t scan;
  /// A removal: a block without a slot or a host copy was never observed, so there is nothing
  /// to undo in it; no slot is taken for it and its cells are not marked.
  bool remove = false;
  /// Marks issued per scratch word (CudaParams::coalesce_ray_marks), else per cell.
  bool coalesce = true;
  /// Misses skip blocks whose cells are all at the lower clamp (never when removing).
  bool skip_saturated = true;
  /// > 0: rays cut into pieces of this many steps of their major axis, shared by the CTA's
  /// threads (CudaParams::ray_piece_steps); 0: one thread a ray. RayCast::kDda only.
  int piece_steps = 0;
  /// Slots below this position of the free stack are not taken (an overflow instead): the
  /// paging budget's room for new blocks (0: the whole stack).
  int32_t free_floor = 0;
};
/// One thread a ray, or pieces of rays (piece_steps): marks FREE / HIT scratch bits, allocating
/// slots for new blocks.
void launchRaycast(const RaycastArgs& args, RayCast mode, bool readonly_loads, cudaStream_t stream);

/// Lists (and stamps) the slots the ray pass marked (ScanCounters::touched must be 0 before).
void launchCompactTouched(const SlotArrays& slots, uint32_t scan, ScanCounters* counters,
                          cudaStream_t stream);

/// MapParams::dynamic in the apply: the void cells voidCells found (8 words a slot, bit c =
/// cell c) replace a miss's update as the CPU backend's apply does (kPassThrough: the cell is
/// set to rule.seen_free_at_or_below_fx; kSurround: rule.afterMiss()). Off: `void_bits` null.
struct DynamicApply {
  DynamicRule rule;
  const uint64_t* void_bits = nullptr;
};

/// Over the touched slots (only when the ray pass had no miss and no overflow): applies the
/// marks (or undoes them: `remove`), clears the scratch, sets dirty / changed_at / last_used.
/// `warp_per_slot`: one warp a slot (CudaParams::warp_per_slot_apply), else a thread block.
void launchApply(const SlotArrays& slots, const OccupancyModel& model, uint64_t revision,
                 uint32_t scan, bool remove, const DynamicApply& dynamic, ScanCounters* counters,
                 int grid, bool warp_per_slot, cudaStream_t stream);

/// The dynamic kernels' view of the scan: the window (after its fill), the slots, the rule.
struct DynamicPassArgs {
  Window window;
  SlotArrays slots;
  ScanCounters* counters;
  int32_t* miss_list;  ///< host-only blocks read (as RaycastArgs::miss_list)
  uint32_t miss_capacity;
  uint32_t scan;
  DynamicRule rule;
  VoxelKey ref;  ///< the rays' reference voxel
  bool octomap_keys = false;
  double inv_res = 0.0;
};

/// Before the ray pass: flags[i] = 1 when ray i is a hit in void space (the CPU's
/// isDynamicHit on the cells as they are before the scan). A host-only block read is listed
/// as a miss (its flags are then not to be used: the host uploads it and launches again).
void launchClassifyDynamic(const DynamicPassArgs& args, const RayEnd* rays, uint32_t num_rays,
                           uint8_t* flags, cudaStream_t stream);

/// The flagged rays become free-only (RayEnd::hit = 0); their point indices (ray_points) go
/// to `points` in any order, ScanCounters::dynamic of them (0 before).
void launchDropDynamic(RayEnd* rays, uint32_t num_rays, const uint8_t* flags,
                       const uint32_t* ray_points, uint32_t* points, ScanCounters* counters,
                       cudaStream_t stream);

/// Between the ray pass's touched list and the apply: the void cells of every touched slot (8
/// words at void_bits[slot * 8]): passThroughResets or surroundedCells of the CPU backend.
/// Host-only blocks read are listed as misses (the apply then skips, the pass is redone).
/// `max_touched`: a bound on ScanCounters::touched (the pool's capacity).
void launchVoidCells(const DynamicPassArgs& args, uint32_t max_touched, uint64_t* void_bits,
                     cudaStream_t stream);

/// free_saturated[slots[j]] = 0 for j < n.
void launchClearSaturated(const SlotArrays& s, const int32_t* slots, uint32_t n,
                          cudaStream_t stream);

/// Window entries: every one kWindowEmpty, then each resident slot whose block is inside.
void launchWindowFill(const Window& w, const SlotArrays& slots, cudaStream_t stream);
/// entries[index[j]] = value[j].
void launchWindowSet(const Window& w, const int64_t* index, const int32_t* value, uint32_t n,
                     cudaStream_t stream);

/// Paging: the kWindowEmpty entries of the boxes of edge^3 blocks starting at first[j]
/// (j < n; regions with a paged-out block) become kWindowHostOnly, so that a ray reaching one
/// records a miss (the region is paged in) rather than creating a block there.
void launchWindowMarkBoxes(const Window& w, const BlockKey* first, uint32_t n, int32_t edge,
                           cudaStream_t stream);
/// Copies block j from src[j] (device-visible: device staging or mapped pinned host memory)
/// and its state masks from masks[j] (device memory) into slot slots[j]; sets its key, clears
/// dirty and fresh, stamps last_used.
void launchUpload(const SlotArrays& s, const Block* const* src, const BlockStateMasks* masks,
                  const int32_t* slots, const BlockKey* keys, uint32_t n, uint32_t scan,
                  cudaStream_t stream);
/// Copies the key of slot slots[j] to keys[j] (j < n): what a direct write-back needs before
/// it makes the host blocks the device writes into.
void launchGatherKeys(const SlotArrays& s, const int32_t* slots, uint32_t n, BlockKey* keys,
                      cudaStream_t stream);
/// Copies slot slots[j] to dst[j], its state masks to masks[j] and its key / changed_at /
/// occupied_at / masks_at to keys[j] / changed_at[j] / changed_at[n + j] / changed_at[2n + j]
/// (changed_at holds 3n values); clears dirty.
void launchDownload(const SlotArrays& s, Block* const* dst, BlockStateMasks* masks,
                    const int32_t* slots, uint32_t n, BlockKey* keys, uint64_t* changed_at,
                    cudaStream_t stream);

/// Device frustum pass over the resident slots (cullBlock, the same test as the host's, with
/// per-slot plane memory): stamps last_used of visible slots.
void launchCullSlots(const SlotArrays& s, const Frustum& f, const CullContext& ctx, double block_m,
                     uint32_t scan, cudaStream_t stream);

}  // namespace fragg::cuda
