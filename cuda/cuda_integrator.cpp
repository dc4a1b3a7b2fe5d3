#include "cuda_integrator.h"

#include <algorithm>
#include <chrono>
#include <string>

#include "fragg_map/internal/seconds_since.h"
#include "kernels.h"

namespace fragg::cuda {

CudaIntegrator::CudaIntegrator(cudaStream_t stream, DeviceBlockCache& cache, int sm_count,
                               int host_threads)
    : stream_(stream),
      cache_(cache),
      sm_count_(sm_count),
      scan_(stream, host_threads),
      window_(stream) {}

bool CudaIntegrator::update(const ScanInput& in, ScanUpdate what, const UpdateSettings& how,
                            BlockMap& blocks, InsertStats& stats) {
  cache_.beginScan();
  dynamic_points_S_.clear();
  const bool dynamic = how.params.dynamic.enabled && what == ScanUpdate::kIntegrate;
  const uint64_t uploaded_before = cache_.uploadedCount();
  const uint64_t evicted_before = cache_.evictedCount();
  InsertStats prep_stats;
  scan_.prepare(in, how.params, cache_.freeSlots(), prep_stats);
  if (scan_.counters().rays == 0) {
    stats.add(prep_stats);
    return true;
  }
  const auto t_ray = std::chrono::steady_clock::now();
  BlockKey lo, hi;
  scan_.rayBlockBox(&lo, &hi);
  if (dynamic) {  // the void tests read every block around a touched one: one block more
    lo = {lo.x - 1, lo.y - 1, lo.z - 1};
    hi = {hi.x + 1, hi.y + 1, hi.z + 1};
  }
  if (!window_.shape(lo, hi)) return false;
  stats.add(prep_stats);

  std::vector<BlockKey> host_only = makeWindowResident(in, how.params.resolution_m, blocks, stats);
  missed_this_scan_.clear();
  uint32_t created = 0;
  try {
    if (dynamic) classifyDynamicHits(in, how, blocks, host_only, stats);
    created = rayAndApply(what, how, blocks, std::move(host_only), stats);
  } catch (const CudaOutOfMemory&) {
    throw;  // the map drops the cache and runs the scan on the CPU
  } catch (...) {
    // A scan refused by the paging budget (or a store that failed to read) leaves its marks
    // unapplied in the pool: they go with the cache, which is written back first.
    cache_.invalidateAll(blocks);
    throw;
  }

  const ScanCounters& c = scan_.counters();
  const double ray_s = apply_start_.secondsSince(ray_start_);
  const double apply_s = apply_end_.secondsSince(apply_start_);
  if (c.changed > 0) cache_.markDirty();
  last_created_ = static_cast<int32_t>(created);
  stats.voxel_visits += c.visits;
  stats.cells_updated += c.cells_updated;
  stats.blocks_touched += c.touched;
  stats.blocks_created += created;
  stats.blocks_uploaded += cache_.uploadedCount() - uploaded_before;
  stats.blocks_evicted += cache_.evictedCount() - evicted_before;
  stats.seconds_apply += apply_s;
  stats.seconds_raycast += ray_s;
  stats.seconds_residency += std::max(0.0, secondsSince(t_ray) - (ray_s + apply_s));
  return true;
}

std::vector<BlockKey> CudaIntegrator::makeWindowResident(const ScanInput& in, double resolution_m,
                                                         BlockMap& blocks, InsertStats& stats) {
  // Host blocks of the window without a slot: those in the frustum (the same cullBlock()
  // test as the CPU's) are uploaded; the others are host-only.
  const double block_m = resolution_m * kBlockSize;
  std::vector<BlockIndex> to_upload;
  std::vector<BlockKey> host_only;
  cache_.forEachHostOnlyIn(blocks, window_.lo(), window_.hi(), [&](BlockIndex i) {
    BlockMeta& m = blocks.meta(i);
    float centre[3];
    const int32_t k[3] = {m.key.x, m.key.y, m.key.z};
    for (int a = 0; a < 3; ++a)
      centre[a] = static_cast<float>((double(k[a]) + 0.5) * block_m - in.frustum.origin_m[a]);
    if (cullBlock(in.frustum, in.cull, centre, static_cast<float>(block_m / 2), m.cull,
                  stats.culling))
      to_upload.push_back(i);
    else
      host_only.push_back(m.key);
  });
  // The resident slots in the frustum are stamped as used by this scan: never evicted by it.
  launchCullSlots(cache_.arrays(), in.frustum, in.cull, block_m, cache_.currentScan(), stream_);
  const int32_t n = static_cast<int32_t>(to_upload.size());
  // Evicted blocks were not visible (visible slots were just stamped): host-only now.
  for (BlockIndex i : cache_.makeRoom(n, n + expectedNewBlocks(), blocks))
    if (window_.contains(blocks.meta(i).key)) host_only.push_back(blocks.meta(i).key);
  cache_.upload(to_upload, blocks);
  return host_only;
}

std::vector<BlockKey> CudaIntegrator::hostOnlyInWindow(const BlockMap& blocks) {
  std::vector<BlockKey> keys;
  cache_.forEachHostOnlyIn(blocks, window_.lo(), window_.hi(),
                           [&](BlockIndex i) { keys.push_back(blocks.meta(i).key); });
  return keys;
}

DynamicPassArgs CudaIntegrator::dynamicArgs(const UpdateSettings& how) const {
  DynamicPassArgs a;
  a.window = window_.window();
  a.slots = cache_.arrays();
  a.counters = scan_.countersOnDevice();
  a.miss_list = scan_.missList();
  a.miss_capacity = scan_.missCapacity();
  a.scan = cache_.currentScan();
  a.rule = DynamicRule::fromParams(how.params.dynamic, how.params.occupancy);
  a.ref = scan_.ref();
  a.octomap_keys = scan_.octomapKeys();
  a.inv_res = scan_.invRes();
  return a;
}

void CudaIntegrator::classifyDynamicHits(const ScanInput& in, const UpdateSettings& how,
                                         BlockMap& blocks, std::vector<BlockKey>& host_only,
                                         InsertStats& stats) {
  ScanCounters& c = scan_.counters();
  const uint32_t n = c.rays;
  dynamic_flags_.reserve(n);
  // The cells as they are before the scan, every block read resident: a pass that read a
  // host-only block listed it; it is uploaded and the pass runs again.
  // Paging: the regions paged out are read like host-only blocks (read back when missed).
  const DevicePaging* paging = how.device_paging;
  std::chrono::steady_clock::time_point first_pass_done;
  for (int attempt = 0;; ++attempt) {
    if (attempt > 8) throw CudaError("dynamic classification did not converge (residency bug)");
    if (attempt > 0) ++stats.passes_redone;
    std::vector<std::pair<BlockKey, BlockKey>> paged_out;
    if (paging) paged_out = paging->paged_out_regions(window_.lo(), window_.hi());
    scan_.reserveMisses(window_.fill(cache_.arrays(), host_only, paged_out));
    scan_.countersToDevice();
    launchClassifyDynamic(dynamicArgs(how), scan_.rays(), n, dynamic_flags_.get(), stream_);
    scan_.countersToHost();
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
    if (c.outside_window != 0)
      throw CudaError("dynamic classification left the window table: residency bug");
    if (attempt == 0) first_pass_done = std::chrono::steady_clock::now();
    if (c.misses == 0) {
      if (attempt > 0) stats.seconds_redone += secondsSince(first_pass_done);
      break;
    }
    resolveMissesAndOverflow(blocks, paging);
    host_only = hostOnlyInWindow(blocks);
    c.misses = 0;
    c.void_misses = 0;
  }
  // The dynamic hits become free-only rays; their points are listed in cloud order.
  c.dynamic = 0;
  dynamic_indices_.reserve(n);
  scan_.countersToDevice();
  launchDropDynamic(scan_.mutableRays(), n, dynamic_flags_.get(), scan_.rayPoints(),
                    dynamic_indices_.device(), scan_.countersOnDevice(), stream_);
  scan_.countersToHost();
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
  dynamic_indices_.toHost(c.dynamic, stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
  std::sort(dynamic_indices_.host(), dynamic_indices_.host() + c.dynamic);
  dynamic_points_S_.reserve(c.dynamic);
  for (uint32_t k = 0; k < c.dynamic; ++k)
    dynamic_points_S_.push_back(in.cloud.points_S[dynamic_indices_.host()[k]]);
  stats.rays_dynamic += c.dynamic;
  stats.rays_hit -= c.dynamic;
}

uint32_t CudaIntegrator::rayAndApply(ScanUpdate what, const UpdateSettings& how, BlockMap& blocks,
                                     std::vector<BlockKey> host_only, InsertStats& stats) {
  ScanCounters& c = scan_.counters();
  // Paging: the regions paged out are missed like host-only blocks (paged in when a ray
  // reaches them), and the rays create no more blocks than the budget has room for.
  const DevicePaging* paging = what == ScanUpdate::kRemove ? nullptr : how.device_paging;
  uint32_t created = 0;
  const bool dynamic_on = how.params.dynamic.enabled && what != ScanUpdate::kRemove;
  // MapParams::dynamic: only the void test lacked blocks, the rays' marks and touched list are
  // complete: the next attempt runs the void test and the apply, not the ray pass again.
  bool marks_complete = false;
  std::chrono::steady_clock::time_point first_pass_done;
  for (int attempt = 0;; ++attempt) {
    if (attempt > 8) throw CudaError("ray pass did not converge (residency bug)");
    if (attempt > 0) ++stats.passes_redone;
    std::vector<std::pair<BlockKey, BlockKey>> paged_out;
    if (paging) paged_out = paging->paged_out_regions(window_.lo(), window_.hi());
    scan_.reserveMisses(window_.fill(cache_.arrays(), host_only, paged_out));
    c.free_top = cache_.freeSlots();
    int32_t floor = 0;
    if (paging) {
      const size_t room = paging->room();
      if (room < size_t(c.free_top)) floor = c.free_top - static_cast<int32_t>(room);
    }
    scan_.countersToDevice();
    RaycastArgs args;
    args.rays = scan_.rays();
    args.num_rays = c.rays;
    args.ref = scan_.ref();
    std::copy(scan_.startV(), scan_.startV() + 3, args.start_v);
    std::copy(scan_.originM(), scan_.originM() + 3, args.origin_m);
    args.resolution_m = how.params.resolution_m;
    args.inv_res = scan_.invRes();
    args.window = window_.window();
    args.slots = cache_.arrays();
    args.miss_list = scan_.missList();
    args.miss_capacity = scan_.missCapacity();
    args.scan = cache_.currentScan();
    args.remove = what == ScanUpdate::kRemove;
    args.coalesce = how.params.cuda.coalesce_ray_marks;
    args.skip_saturated = how.params.skip_saturated_blocks && !args.remove;
    args.piece_steps = how.params.cuda.ray_piece_steps;
    args.free_floor = floor;
    args.counters = scan_.countersOnDevice();
    ray_start_.record(stream_);
    if (!marks_complete) {
      launchRaycast(args, how.params.raycast, how.params.cuda.readonly_ray_loads, stream_);
      launchCompactTouched(args.slots, args.scan, args.counters, stream_);
    }
    // MapParams::dynamic: the void cells of the touched slots, from the cells and marks as
    // they are before the apply (a host-only block read is a miss: uploaded, then redone).
    DynamicApply dynamic;
    if (dynamic_on) {
      dynamic.rule = DynamicRule::fromParams(how.params.dynamic, how.params.occupancy);
      void_bits_.reserve(size_t(args.slots.capacity) * (kCellsPerBlock / 64));
      dynamic.void_bits = void_bits_.get();
      launchVoidCells(dynamicArgs(how), static_cast<uint32_t>(args.slots.capacity),
                      void_bits_.get(), stream_);
    }
    apply_start_.record(stream_);
    launchApply(args.slots, how.model, how.revision, args.scan, args.remove, dynamic, args.counters,
                16 * sm_count_, how.params.cuda.warp_per_slot_apply, stream_);
    apply_end_.record(stream_);
    scan_.countersToHost();
    pass_done_.record(stream_);
    // A batch's next cloud goes up while the device works on this pass (its host copy is
    // what overlaps); a redone pass queues behind that upload.
    if (attempt == 0 && how.stage_next) stageNext(*how.stage_next, how.stage_next_auto_stats);
    pass_done_.synchronize();
    if (c.outside_window != 0)
      throw CudaError("ray left the window table (" + std::to_string(c.outside_window) +
                      " cells): residency bug");
    // The slots the rays took are resident blocks, device-only until written back.
    created += cache_.adoptDeviceSlots(std::max(c.free_top, floor));
    if (attempt == 0) first_pass_done = std::chrono::steady_clock::now();
    if (c.applied) {
      if (attempt > 0) stats.seconds_redone += secondsSince(first_pass_done);
      return created;
    }
    // The pass is redone from a clean count: the marks and allocations stay (touched slots
    // are stamped: never evicted to make room).
    marks_complete = dynamic_on && c.overflow == 0 && c.misses == c.void_misses;
    resolveMissesAndOverflow(blocks, paging);
    host_only = hostOnlyInWindow(blocks);  // evictions may have touched the window's blocks
    c.misses = 0;
    c.void_misses = 0;
    c.overflow = 0;
    if (!marks_complete) {
      c.visits = 0;
      c.touched = 0;  // listed again after the next pass
    }
  }
}

void CudaIntegrator::stageNext(const PointCloud& cloud, bool auto_stats) {
  try {
    scan_.stageAhead(cloud, auto_stats);
  } catch (const CudaOutOfMemory&) {
    // Staging is an optimisation: the next scan uploads its own points (and meets the same).
  }
}

void CudaIntegrator::resolveMissesAndOverflow(BlockMap& blocks, const DevicePaging* paging) {
  const ScanCounters& c = scan_.counters();
  std::vector<BlockKey> missed;
  if (c.misses > 0)
    for (int32_t entry : scan_.misses(c.misses)) missed.push_back(window_.window().keyOf(entry));
  if (paging) {
    // The missed blocks the host map lacks are in paged-out regions: read back, with room made
    // under the budget for them and for the blocks the overflowed rays create; the regions of
    // the blocks this scan marked stay.
    std::vector<BlockKey> reached;
    for (const BlockKey& k : missed)
      if (blocks.find(k) == kNoBlock) reached.push_back(k);
    // The blocks missed in the scan's passes stay while it runs: a ray that skips a saturated
    // block marks nothing there, and paging it out again would miss it again.
    missed_this_scan_.insert(missed_this_scan_.end(), missed.begin(), missed.end());
    const size_t new_blocks = c.overflow;
    if (!reached.empty() || paging->room() < new_blocks) {
      // The blocks the rays marked stay (a ray passes through every block it reaches in one
      // pass, so the next pass reaches no other); the frustum's other blocks may leave, and
      // the blocks earlier scans made on the device (written back first: Map::devicePaging).
      std::vector<BlockKey> pinned = cache_.keysMarked(c.touched);
      pinned.insert(pinned.end(), missed_this_scan_.begin(), missed_this_scan_.end());
      paging->make_room(reached, pinned, new_blocks);
    }
  }
  if (!missed.empty()) {
    std::vector<BlockIndex> needed;
    for (const BlockKey& k : missed) {
      const BlockIndex i = blocks.find(k);
      if (i == kNoBlock) {
        // Paged in with its region and not in the store: a ray creates it next pass.
        if (paging) continue;
        throw CudaError("missed block is not on the host (residency bug)");
      }
      if (cache_.slotOf(i) < 0) needed.push_back(i);
    }
    const int32_t n = static_cast<int32_t>(needed.size());
    cache_.makeRoom(n, n, blocks);
    cache_.upload(needed, blocks);
  }
  if (c.overflow > 0)
    cache_.makeRoom(static_cast<int32_t>(c.overflow),
                    static_cast<int32_t>(c.overflow) * 2 + expectedNewBlocks(), blocks);
}

}  // namespace fragg::cuda
