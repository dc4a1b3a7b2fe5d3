#include "cuda_integrator.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>

#include "fragg_map/internal/cuda_backend.h"
#include "fragg_map/internal/prepared_scan.h"
#include "fragg_map/log.h"
#include "kernels.h"
#include "pinned_allocator.h"

namespace fragg {

std::unique_ptr<Integrator> makeCudaIntegrator(const MapParams& params) {
  return std::make_unique<cuda::CudaIntegrator>(params);
}

namespace cuda {

namespace {
/// Largest window table (entries, 4 bytes each); a scan whose rays span more goes to the CPU.
constexpr int64_t kMaxWindowEntries = int64_t(1) << 27;
/// Blocks moved per transfer batch (32 MiB of staging).
constexpr size_t kTransferBatch = 16384;
constexpr double kPi = 3.14159265358979323846;

int selectDevice(int device) {
  FRAGG_CUDA_CHECK(cudaSetDevice(device));
  return device;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

CudaIntegrator::CudaIntegrator(const MapParams& params)
    : params_(params),
      host_allocator_(params.cuda.pinned_host_blocks ? pinnedChunkAllocator()
                                                     : plainChunkAllocator()),
      direct_uploads_(params.cuda.pinned_host_blocks),
      device_(selectDevice(params.cuda.device)),
      pool_(stream_.get()),
      cpu_(params.threads) {
  FRAGG_CUDA_CHECK(
      cudaDeviceGetAttribute(&sm_count_, cudaDevAttrMultiProcessorCount, params.cuda.device));
  int unified = 0;
  FRAGG_CUDA_CHECK(
      cudaDeviceGetAttribute(&unified, cudaDevAttrUnifiedAddressing, params.cuda.device));
  if (!unified) direct_uploads_ = false;  // pinned host memory not addressable in place
  FRAGG_CUDA_CHECK(cudaEventCreate(&ray_start_));
  FRAGG_CUDA_CHECK(cudaEventCreate(&apply_start_));
  FRAGG_CUDA_CHECK(cudaEventCreate(&apply_end_));
  counters_dev_.resize(1);
  counters_host_.reserve(1);
}

CudaIntegrator::~CudaIntegrator() {
  if (ray_start_) cudaEventDestroy(ray_start_);
  if (apply_start_) cudaEventDestroy(apply_start_);
  if (apply_end_) cudaEventDestroy(apply_end_);
}

size_t CudaIntegrator::deviceBytes() const {
  return pool_.deviceBytes() + window_dev_.bytes() + rays_dev_.bytes() + points_dev_.bytes() +
         staging_dev_.bytes() + miss_dev_.bytes();
}

int32_t CudaIntegrator::slotLimit() const {
  size_t bytes = params_.cuda.pool_max_bytes;
  if (bytes == 0) {
    size_t free_bytes = 0, total_bytes = 0;
    FRAGG_CUDA_CHECK(cudaMemGetInfo(&free_bytes, &total_bytes));
    bytes = pool_.deviceBytes() + free_bytes / 2;
  }
  return static_cast<int32_t>(std::min<size_t>(bytes / SlotPool::bytesPerSlot(), INT32_MAX / 2));
}

void CudaIntegrator::sizePool(const SensorModel& model, double resolution_m) {
  if (pool_.capacity() > 0) return;
  // The paper's formula (1)-(4) for a pinhole; the spherical shell sector for a LiDAR.
  const double block_m = resolution_m * kBlockSize;
  double blocks = 0.0;
  if (model.type == SensorType::kPinhole) {
    blocks =
        frustumVoxelEstimate(std::max(model.hfov_rad, model.vfov_rad),
                             model.max_range_m - model.min_range_m, model.min_range_m, block_m);
  } else {
    const double r = model.max_range_m, r0 = model.min_range_m;
    const double volume = 2.0 * kPi / 3.0 * (r * r * r - r0 * r0 * r0) *
                          (std::sin(model.elevation_max_rad) - std::sin(model.elevation_min_rad));
    blocks = volume / (block_m * block_m * block_m);
  }
  estimate_blocks_ = static_cast<int64_t>(std::ceil(blocks));
  const double wanted = std::max(4096.0, blocks * params_.cuda.pool_margin);
  pool_.grow(static_cast<int32_t>(std::min<double>(wanted, slotLimit())));
  block_of_slot_.assign(size_t(pool_.capacity()), kNoBlock);
}

void CudaIntegrator::setSlotOf(BlockIndex i, int32_t slot) {
  if (i >= slot_of_block_.size()) slot_of_block_.resize(size_t(i) + 1 + i / 2, -1);
  slot_of_block_[i] = slot;
}

void CudaIntegrator::makeRoom(int32_t need, int32_t want, BlockMap& blocks) {
  want = std::max(want, need);
  if (pool_.freeTop() >= want) return;
  const int32_t cap = pool_.capacity();
  const int32_t limit = slotLimit();
  const int64_t grown =
      std::max<int64_t>(int64_t(cap) + cap / 2, int64_t(cap) + want - pool_.freeTop());
  if (cap < limit) {
    try {
      pool_.grow(static_cast<int32_t>(std::min<int64_t>(grown, limit)));
      block_of_slot_.resize(size_t(pool_.capacity()), kNoBlock);
    } catch (const CudaOutOfMemory&) {
      // Stay at this size; evict below.
    }
  }
  if (pool_.freeTop() < want) evict(want - pool_.freeTop(), blocks);
  if (pool_.freeTop() < need)
    throw CudaOutOfMemory("device block pool of " + std::to_string(pool_.capacity()) +
                          " slots cannot hold the blocks of one scan");
}

void CudaIntegrator::evict(int32_t n, BlockMap& blocks) {
  const int32_t cap = pool_.capacity();
  last_used_host_.reserve(size_t(cap));
  dirty_host_.reserve(size_t(cap));
  const SlotArrays a = pool_.arrays();
  copyToHost(last_used_host_.get(), a.last_used, size_t(cap), stream_.get());
  copyToHost(dirty_host_.get(), a.dirty, size_t(cap), stream_.get());
  stream_.sync();
  std::vector<uint8_t>& resident = pool_.residentHost();
  std::vector<int32_t> candidates;
  for (int32_t s = 0; s < cap; ++s)
    if (resident[s] && last_used_host_[s] != scan_) candidates.push_back(s);
  const size_t k = std::min(candidates.size(), size_t(n));
  std::partial_sort(candidates.begin(), candidates.begin() + k, candidates.end(),
                    [&](int32_t x, int32_t y) { return last_used_host_[x] < last_used_host_[y]; });
  candidates.resize(k);
  std::vector<int32_t> dirty;
  for (int32_t s : candidates)
    if (dirty_host_[s]) dirty.push_back(s);
  writeBack(dirty, blocks);
  for (int32_t s : candidates) {
    resident[s] = 0;
    const BlockIndex i = block_of_slot_[s];  // kNoBlock: device-only and never applied
    if (i != kNoBlock) {
      setSlotOf(i, -1);
      host_only_.add(i, blocks.meta(i).key);
    }
    block_of_slot_[s] = kNoBlock;
  }
  pool_.uploadResident();
  pool_.push(candidates);
  evicted_ += candidates.size();
}

void CudaIntegrator::reserveTransfer(size_t n, bool staging) {
  ptrs_host_.reserve(n);
  ptrs_dev_.reserve(n);
  slots_host_.reserve(n);
  slots_dev_.reserve(n);
  keys_host_.reserve(n);
  keys_dev_.reserve(n);
  if (staging) {
    staging_host_.reserve(n);
    staging_dev_.reserve(n);
  }
}

void CudaIntegrator::writeBack(const std::vector<int32_t>& slots, BlockMap& blocks) {
  const SlotArrays a = pool_.arrays();
  for (size_t begin = 0; begin < slots.size(); begin += kTransferBatch) {
    const size_t n = std::min(kTransferBatch, slots.size() - begin);
    reserveTransfer(n, /*staging=*/true);
    changed_host_.reserve(2 * n);  // changed_at, then occupied_at
    changed_dev_.reserve(2 * n);
    for (size_t j = 0; j < n; ++j) {
      slots_host_[j] = slots[begin + j];
      ptrs_host_[j] = staging_dev_.get() + j;
    }
    copyToDevice(slots_dev_.get(), slots_host_.get(), n, stream_.get());
    copyToDevice(ptrs_dev_.get(), ptrs_host_.get(), n, stream_.get());
    launchDownload(a, ptrs_dev_.get(), slots_dev_.get(), uint32_t(n), keys_dev_.get(),
                   changed_dev_.get(), stream_.get());
    copyToHost(staging_host_.get(), staging_dev_.get(), n, stream_.get());
    copyToHost(keys_host_.get(), keys_dev_.get(), n, stream_.get());
    copyToHost(changed_host_.get(), changed_dev_.get(), 2 * n, stream_.get());
    stream_.sync();
    // New host blocks first (the index is not thread-safe), then the copies in parallel.
    std::vector<BlockIndex> target(n);
    for (size_t j = 0; j < n; ++j) {
      const int32_t s = slots_host_[j];
      if (block_of_slot_[s] == kNoBlock) {
        const BlockIndex i = blocks.findOrCreate(keys_host_[j], nullptr, /*initialise=*/false);
        block_of_slot_[s] = i;
        setSlotOf(i, s);
      }
      target[j] = block_of_slot_[s];
    }
#pragma omp parallel for schedule(static)
    for (long j = 0; j < static_cast<long>(n); ++j) {
      std::memcpy(&blocks.block(target[j]), &staging_host_[j], sizeof(Block));
      BlockMeta& m = blocks.meta(target[j]);
      m.changed_at = std::max(m.changed_at, changed_host_[j]);
      m.occupied_at = std::max(m.occupied_at, changed_host_[n + j]);
    }
  }
}

std::vector<int32_t> CudaIntegrator::upload(const std::vector<BlockIndex>& host_blocks,
                                            BlockMap& blocks) {
  std::vector<int32_t> slots = pool_.pop(static_cast<int32_t>(host_blocks.size()));
  const SlotArrays a = pool_.arrays();
  for (size_t begin = 0; begin < host_blocks.size(); begin += kTransferBatch) {
    const size_t n = std::min(kTransferBatch, host_blocks.size() - begin);
    reserveTransfer(n, /*staging=*/!direct_uploads_);
#pragma omp parallel for schedule(static)
    for (long j = 0; j < static_cast<long>(n); ++j) {
      const BlockIndex i = host_blocks[begin + j];
      slots_host_[j] = slots[begin + j];
      keys_host_[j] = blocks.meta(i).key;
      if (direct_uploads_) {
        ptrs_host_[j] = &blocks.block(i);
      } else {
        std::memcpy(&staging_host_[j], &blocks.block(i), sizeof(Block));
        ptrs_host_[j] = staging_dev_.get() + j;
      }
    }
    if (!direct_uploads_) copyToDevice(staging_dev_.get(), staging_host_.get(), n, stream_.get());
    copyToDevice(ptrs_dev_.get(), ptrs_host_.get(), n, stream_.get());
    copyToDevice(slots_dev_.get(), slots_host_.get(), n, stream_.get());
    copyToDevice(keys_dev_.get(), keys_host_.get(), n, stream_.get());
    launchUpload(a, reinterpret_cast<const Block* const*>(ptrs_dev_.get()), slots_dev_.get(),
                 keys_dev_.get(), uint32_t(n), scan_, stream_.get());
    stream_.sync();  // the pinned buffers are reused by the next batch
  }
  std::vector<uint8_t>& resident = pool_.residentHost();
  for (size_t j = 0; j < host_blocks.size(); ++j) {
    resident[slots[j]] = 1;
    block_of_slot_[slots[j]] = host_blocks[j];
    setSlotOf(host_blocks[j], slots[j]);
    host_only_.remove(host_blocks[j], blocks.meta(host_blocks[j]).key);
  }
  uploaded_ += host_blocks.size();
  return slots;
}

void CudaIntegrator::setWindowEntries(const std::vector<int64_t>& index,
                                      const std::vector<int32_t>& value) {
  const size_t n = index.size();
  if (n == 0) return;
  widx_host_.reserve(n);
  widx_dev_.reserve(n);
  wval_host_.reserve(n);
  wval_dev_.reserve(n);
  std::copy(index.begin(), index.end(), widx_host_.get());
  std::copy(value.begin(), value.end(), wval_host_.get());
  copyToDevice(widx_dev_.get(), widx_host_.get(), n, stream_.get());
  copyToDevice(wval_dev_.get(), wval_host_.get(), n, stream_.get());
  launchWindowSet(window_, widx_dev_.get(), wval_dev_.get(), uint32_t(n), stream_.get());
  stream_.sync();
}

void CudaIntegrator::fillWindow(const std::vector<BlockIndex>& host_only, const BlockMap& blocks) {
  launchWindowFill(window_, pool_.arrays(), stream_.get());
  std::vector<int64_t> index;
  index.reserve(host_only.size());
  for (BlockIndex i : host_only) index.push_back(window_.indexOf(blocks.meta(i).key));
  setWindowEntries(index, std::vector<int32_t>(index.size(), kWindowHostOnly));
  miss_dev_.reserve(std::max<size_t>(host_only.size(), 1));
  miss_host_.reserve(std::max<size_t>(host_only.size(), 1));
}

uint32_t CudaIntegrator::adoptDeviceSlots(int32_t new_free_top) {
  // Slots the rays took are resident blocks that exist on the device only, until written back.
  const std::vector<int32_t> taken = pool_.takenByDevice(new_free_top);
  for (int32_t s : taken) {
    pool_.residentHost()[s] = 1;
    block_of_slot_[s] = kNoBlock;
  }
  return static_cast<uint32_t>(taken.size());
}

bool CudaIntegrator::prepareOnDevice(const ScanInput& in, const MapParams& params,
                                     InsertStats& stats) {
  const auto t0 = std::chrono::steady_clock::now();
  const PointCloud& cloud = in.cloud;
  const size_t n = cloud.size();
  ScanCounters& c = counters_host_[0];
  c = ScanCounters{};
  for (int a = 0; a < 3; ++a) {
    c.lo_v[a] = 0;  // the start cell is part of the box
    c.hi_v[a] = 0;
  }
  c.free_top = pool_.freeTop();
  if (params.clear_no_return_rays && cloud.organised()) {
    // No-return rays need the row neighbours' directions: prepared on the host.
    prepareScan(cloud, in.T_map_sensor, in.model, in.frustum, in.explicit_model, params,
                host_prepared_, stats);
    ref_ = host_prepared_.ref;
    std::copy(host_prepared_.start_v, host_prepared_.start_v + 3, start_v_);
    c.rays = static_cast<uint32_t>(host_prepared_.rays.size());
    for (const RayEnd& r : host_prepared_.rays)
      for (int a = 0; a < 3; ++a) {
        c.lo_v[a] = std::min(c.lo_v[a], floorToInt(r.end_v[a]));
        c.hi_v[a] = std::max(c.hi_v[a], floorToInt(r.end_v[a]));
      }
    rays_dev_.reserve(c.rays);
    copyToDevice(rays_dev_.get(), host_prepared_.rays.data(), c.rays, stream_.get());
    copyToDevice(counters_dev_.get(), counters_host_.get(), 1, stream_.get());
    stream_.sync();
    stats.seconds_prepare += secondsSince(t0);
    return true;
  }
  const RayPrepParams prep =
      rayPrepParams(in.T_map_sensor, in.model, in.explicit_model, params, host_prepared_);
  ref_ = host_prepared_.ref;
  std::copy(host_prepared_.start_v, host_prepared_.start_v + 3, start_v_);
  for (int a = 0; a < 3; ++a) {
    c.lo_v[a] = 0;
    c.hi_v[a] = 0;
  }
  points_host_.reserve(3 * n);
  points_dev_.reserve(3 * n);
  rays_dev_.reserve(n);
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "packed points");
  const float* src = reinterpret_cast<const float*>(cloud.points_S.data());
  float* dst = points_host_.get();
#pragma omp parallel for schedule(static)
  for (long chunk = 0; chunk < 64; ++chunk) {
    const size_t b = 3 * n * size_t(chunk) / 64, e = 3 * n * size_t(chunk + 1) / 64;
    std::memcpy(dst + b, src + b, (e - b) * sizeof(float));
  }
  copyToDevice(points_dev_.get(), points_host_.get(), 3 * n, stream_.get());
  copyToDevice(counters_dev_.get(), counters_host_.get(), 1, stream_.get());
  launchPrepare(points_dev_.get(), uint32_t(n), prep, in.frustum, rays_dev_.get(),
                counters_dev_.get(), stream_.get());
  copyToHost(counters_host_.get(), counters_dev_.get(), 1, stream_.get());
  stream_.sync();
  stats.points_in += n;
  stats.rays_hit += c.hits;
  stats.rays_free_only += c.free_only;
  stats.dropped_invalid += c.invalid;
  stats.dropped_min_range += c.too_close;
  stats.dropped_outside_frustum += c.outside;
  stats.seconds_prepare += secondsSince(t0);
  return true;
}

void CudaIntegrator::integrateOnCpu(const ScanInput& in, const MapParams& params,
                                    const OccupancyModel& model, uint64_t revision,
                                    BlockMap& blocks, InsertStats& stats, const char* why) {
  static bool said = false;
  if (!said) {
    logMessage(LogLevel::kWarning, std::string("a scan ran on the CPU backend: ") + why);
    said = true;
  }
  syncToHost(blocks);
  dropDeviceCopies();
  cpu_.integrate(in, params, model, revision, blocks, stats);
}

void CudaIntegrator::integrate(const ScanInput& in, const MapParams& params,
                               const OccupancyModel& model, uint64_t revision, BlockMap& blocks,
                               InsertStats& stats) {
  ++scan_;
  const uint64_t uploaded_before = uploaded_, evicted_before = evicted_;
  sizePool(in.model, params.resolution_m);
  InsertStats prep_stats;
  prepareOnDevice(in, params, prep_stats);
  ScanCounters& c = counters_host_[0];
  if (c.rays == 0) {
    stats.add(prep_stats);
    return;
  }

  // 1. The window: the rays' box of blocks (start cell included).
  const auto t_ray = std::chrono::steady_clock::now();
  const int32_t ref[3] = {ref_.x, ref_.y, ref_.z};
  Window w;
  int64_t entries = 1;
  for (int a = 0; a < 3; ++a) {
    w.lo[a] = (ref[a] + c.lo_v[a] - 1) >> kBlockBits;
    const int32_t hi = (ref[a] + c.hi_v[a] + 1) >> kBlockBits;
    w.dim[a] = hi - w.lo[a] + 1;
    entries *= w.dim[a];
  }
  if (entries > kMaxWindowEntries) {
    integrateOnCpu(in, params, model, revision, blocks, stats,
                   "its rays span more blocks than the device window table holds");
    return;
  }
  stats.add(prep_stats);
  window_dev_.reserve(size_t(entries));
  w.entries = window_dev_.get();
  window_ = w;

  // 2. Residency. Visible host blocks of the window are uploaded now; the window's other host
  // blocks are marked host-only (a ray that needs one reports it and the pass is redone).
  if (host_only_stale_) {
    host_only_.rebuild(blocks);
    host_only_stale_ = false;
  }
  const BlockKey wlo{w.lo[0], w.lo[1], w.lo[2]};
  const BlockKey whi{w.lo[0] + w.dim[0] - 1, w.lo[1] + w.dim[1] - 1, w.lo[2] + w.dim[2] - 1};
  std::vector<BlockIndex> to_upload, host_only;
  // Host blocks of the window without a slot. eager: those in the frustum (the same
  // cullBlock() test as the CPU's) go to the upload list; the others are host-only.
  const double block_m = params.resolution_m * kBlockSize;
  auto classify = [&](bool eager) {
    to_upload.clear();
    host_only.clear();
    host_only_.forEachInBox(blocks, wlo, whi, [&](BlockIndex i) {
      BlockMeta& m = blocks.meta(i);
      float centre[3];
      const int32_t k[3] = {m.key.x, m.key.y, m.key.z};
      for (int a = 0; a < 3; ++a)
        centre[a] = static_cast<float>((double(k[a]) + 0.5) * block_m - in.frustum.origin_m[a]);
      if (eager && cullBlock(in.frustum, in.cull, centre, static_cast<float>(block_m / 2), m.cull,
                             stats.culling))
        to_upload.push_back(i);
      else
        host_only.push_back(i);
    });
  };
  classify(true);
  const SlotArrays before = pool_.arrays();
  CullContext ctx = in.cull;
  launchCullSlots(before, in.frustum, ctx, block_m, scan_, stream_.get());
  const int32_t expected_new = std::max<int32_t>(1024, last_created_ + last_created_ / 4);
  const uint64_t evicted_pre = evicted_;
  makeRoom(static_cast<int32_t>(to_upload.size()),
           static_cast<int32_t>(to_upload.size()) + expected_new, blocks);
  if (evicted_ != evicted_pre) classify(true);  // evicted window blocks: host-only now
  upload(to_upload, blocks);

  // 3. Window table.
  fillWindow(host_only, blocks);

  // 4. Ray pass and apply; redone after a miss or an overflow (marks are idempotent).
  c.free_top = pool_.freeTop();
  copyToDevice(counters_dev_.get(), counters_host_.get(), 1, stream_.get());
  uint32_t created = 0;
  for (int attempt = 0;; ++attempt) {
    if (attempt > 8) throw CudaError("ray pass did not converge (residency bug)");
    RaycastArgs args;
    args.rays = rays_dev_.get();
    args.num_rays = c.rays;
    args.ref = ref_;
    std::copy(start_v_, start_v_ + 3, args.start_v);
    args.window = window_;
    args.slots = pool_.arrays();
    args.miss_list = miss_dev_.get();
    args.miss_capacity = static_cast<uint32_t>(miss_dev_.size());
    args.counters = counters_dev_.get();
    args.scan = scan_;
    args.remove = in.remove;
    FRAGG_CUDA_CHECK(cudaEventRecord(ray_start_, stream_.get()));
    launchRaycast(args, params.raycast, params.cuda.readonly_ray_loads, stream_.get());
    launchCompactTouched(pool_.arrays(), scan_, counters_dev_.get(), stream_.get());
    FRAGG_CUDA_CHECK(cudaEventRecord(apply_start_, stream_.get()));
    launchApply(pool_.arrays(), model, revision, scan_, in.remove, counters_dev_.get(),
                16 * sm_count_, stream_.get());
    FRAGG_CUDA_CHECK(cudaEventRecord(apply_end_, stream_.get()));
    copyToHost(counters_host_.get(), counters_dev_.get(), 1, stream_.get());
    stream_.sync();
    if (c.outside_window != 0)
      throw CudaError("ray left the window table (" + std::to_string(c.outside_window) +
                      " cells): residency bug");
    if (c.applied) break;
    // The pass is redone from a clean count: the marks and allocations stay.
    created += adoptDeviceSlots(c.free_top);
    if (c.misses > 0) {
      std::vector<BlockIndex> needed;
      const uint32_t listed = std::min<uint32_t>(c.misses, uint32_t(miss_dev_.size()));
      copyToHost(miss_host_.get(), miss_dev_.get(), listed, stream_.get());
      stream_.sync();
      for (uint32_t k = 0; k < listed; ++k) {
        const BlockIndex i = blocks.find(window_.keyOf(miss_host_[k]));
        if (i == kNoBlock) throw CudaError("missed block is not on the host (residency bug)");
        needed.push_back(i);
      }
      makeRoom(static_cast<int32_t>(needed.size()), static_cast<int32_t>(needed.size()), blocks);
      upload(needed, blocks);
    }
    if (c.overflow > 0)
      makeRoom(static_cast<int32_t>(c.overflow),
               static_cast<int32_t>(c.overflow) * 2 + expected_new, blocks);
    // Evictions may have touched the window's blocks: build the table again.
    classify(false);
    fillWindow(host_only, blocks);
    c.misses = 0;
    c.overflow = 0;
    c.visits = 0;
    c.touched = 0;  // listed again after the next pass
    c.free_top = pool_.freeTop();
    copyToDevice(counters_dev_.get(), counters_host_.get(), 1, stream_.get());
  }
  created += adoptDeviceSlots(c.free_top);
  float ray_ms = 0.f, apply_ms = 0.f;
  FRAGG_CUDA_CHECK(cudaEventElapsedTime(&ray_ms, ray_start_, apply_start_));
  FRAGG_CUDA_CHECK(cudaEventElapsedTime(&apply_ms, apply_start_, apply_end_));
  if (c.changed > 0) any_dirty_ = true;
  last_created_ = static_cast<int32_t>(created);
  stats.voxel_visits += c.visits;
  stats.cells_updated += c.cells_updated;
  stats.blocks_touched += c.touched;
  stats.blocks_created += created;
  stats.blocks_uploaded += uploaded_ - uploaded_before;
  stats.blocks_evicted += evicted_ - evicted_before;
  stats.seconds_apply += apply_ms * 1e-3;
  stats.seconds_raycast += ray_ms * 1e-3;
  stats.seconds_residency += std::max(0.0, secondsSince(t_ray) - (ray_ms + apply_ms) * 1e-3);
}

void CudaIntegrator::syncToHost(BlockMap& blocks) {
  if (!any_dirty_) return;
  const int32_t cap = pool_.capacity();
  dirty_host_.reserve(size_t(cap));
  copyToHost(dirty_host_.get(), pool_.arrays().dirty, size_t(cap), stream_.get());
  stream_.sync();
  std::vector<int32_t> dirty;
  for (int32_t s = 0; s < cap; ++s)
    if (dirty_host_[s]) dirty.push_back(s);
  writeBack(dirty, blocks);
  any_dirty_ = false;
}

void CudaIntegrator::dropDeviceCopies() {
  pool_.clear();
  std::fill(block_of_slot_.begin(), block_of_slot_.end(), kNoBlock);
  std::fill(slot_of_block_.begin(), slot_of_block_.end(), -1);
  host_only_.clear();
  host_only_stale_ = true;  // the host map is about to change: rebuilt at the next scan
  any_dirty_ = false;
}

}  // namespace cuda
}  // namespace fragg
