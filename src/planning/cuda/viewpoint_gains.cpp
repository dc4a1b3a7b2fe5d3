#include "viewpoint_gains.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "cuda_check.h"
#include "cuda_stream.h"
#include "fragg_map/errors.h"
#include "fragg_map/internal/seconds_since.h"
#include "gain_kernels.h"

namespace fragg::planning {

namespace {

/// Device memory for the bitmaps of one round of viewpoints: a quarter of what the device has
/// free, within these bounds (fewer rounds, fewer kernel tails).
constexpr uint64_t kSeenBudgetMinBytes = uint64_t(1) << 30;
constexpr uint64_t kSeenBudgetMaxBytes = uint64_t(4) << 30;
constexpr uint64_t kMaxSeenBytesPerViewpoint = uint64_t(4) << 30;
/// The largest dense block table over a batch's reach (entries of 4 bytes); a larger reach
/// looks blocks up in the view's hash.
constexpr uint64_t kMaxDenseEntries = uint64_t(1) << 26;

/// The walk's buffers in the scratch (device buffer ids; pinned ids for the read-backs).
enum Buffer : int {
  kOrigins = 200,
  kCos,
  kSin,
  kRays,
  kGains,
  kSeen,
  kBoxLo,
  kDense,
  kBoxDims,
  kSeenOffset,
  kDirectoryOffset,
  kDirectory,
  kPool,
  kQueue,
  kPoolTaken,
  kOverflow,
  kPoolOwner
};
enum PinnedBuffer : int { kPinnedOverflow = 200, kPinnedCounters };
/// The pool's share of the bitmap budget (the directories get the rest).
constexpr double kPoolShare = 0.75;
/// Bytes of a pool bitmap (one block's 512 cells).
constexpr uint64_t kPoolBitmapBytes = 64;

/// Half the side of the cube around a viewpoint's cell that holds every cell its rays enter.
int halfSideOf(const GainBatch& batch) { return static_cast<int>(std::ceil(batch.length_v)) + 2; }

/// Each viewpoint's cell bitmap box (voxel keys): its own size, and the largest (the plain
/// kernel gives every viewpoint that one).
struct SeenBoxes {
  std::vector<int32_t> lo;        ///< 3 per viewpoint
  std::vector<int32_t> own_dims;  ///< 3 per viewpoint
  int32_t dims[3] = {0, 0, 0};
  uint64_t words = 0;  ///< 64-bit words of one bitmap of the largest size
};

/// The boxes of the cells each viewpoint's rays can enter: the sensor-frame box of the ray
/// directions and the origin, turned by the viewpoint's yaw (its four corners), times the
/// length, with two cells to spare on each side (a DDA step enters the cell beyond a face;
/// rounding), and never past the cube of +- halfSideOf around the origin cell. The bitmaps
/// shrink from that cube to the field of view (a pinhole's wedge, a LiDAR's elevation band):
/// less to clear and denser atomics.
SeenBoxes seenBoxes(const GainBatch& batch) {
  const size_t n = batch.viewpoints(), n_rays = batch.rays();
  double rmin[3] = {0.0, 0.0, 0.0}, rmax[3] = {0.0, 0.0, 0.0};
  for (size_t r = 0; r < n_rays; ++r)
    for (int a = 0; a < 3; ++a) {
      rmin[a] = std::min(rmin[a], batch.rays_sensor[3 * r + a]);
      rmax[a] = std::max(rmax[a], batch.rays_sensor[3 * r + a]);
    }
  const int half = halfSideOf(batch);
  const double length = batch.length_v;
  SeenBoxes boxes;
  boxes.lo.resize(3 * n);
  boxes.own_dims.resize(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const double c = batch.cos_yaw[i], s = batch.sin_yaw[i];
    double lo_d[3] = {0.0, 0.0, rmin[2]}, hi_d[3] = {0.0, 0.0, rmax[2]};
    for (const double x : {rmin[0], rmax[0]})
      for (const double y : {rmin[1], rmax[1]}) {
        const double turned[2] = {c * x - s * y, s * x + c * y};
        for (int a = 0; a < 2; ++a) {
          lo_d[a] = std::min(lo_d[a], turned[a]);
          hi_d[a] = std::max(hi_d[a], turned[a]);
        }
      }
    for (int a = 0; a < 3; ++a) {
      const double o = batch.origins_v[3 * i + a];
      const int64_t centre = static_cast<int64_t>(std::floor(o));
      const int64_t lo = std::max<int64_t>(
          centre - half, static_cast<int64_t>(std::floor(o + length * lo_d[a])) - 2);
      const int64_t top = std::min<int64_t>(
          centre + half, static_cast<int64_t>(std::floor(o + length * hi_d[a])) + 2);
      boxes.lo[3 * i + a] = static_cast<int32_t>(lo);
      boxes.own_dims[3 * i + a] = static_cast<int32_t>(top - lo + 1);
      boxes.dims[a] = std::max(boxes.dims[a], boxes.own_dims[3 * i + a]);
    }
  }
  boxes.words =
      (uint64_t(boxes.dims[0]) * uint64_t(boxes.dims[1]) * uint64_t(boxes.dims[2]) + 63) / 64;
  return boxes;
}

/// 64-bit words of viewpoint i's bitmap of its own size.
uint64_t ownWords(const SeenBoxes& boxes, size_t i) {
  const int32_t* d = &boxes.own_dims[3 * i];
  return (uint64_t(d[0]) * uint64_t(d[1]) * uint64_t(d[2]) + 63) / 64;
}

/// Entries of viewpoint i's pooled directory: the blocks its box touches.
uint64_t directoryEntries(const SeenBoxes& boxes, size_t i) {
  return PoolDirectory::over(&boxes.lo[3 * i], &boxes.own_dims[3 * i]).entries();
}

/// Rounds of consecutive viewpoints whose `sizes` sum to at most `budget` (a viewpoint larger
/// than the budget alone), at most `max_count` a round: the first viewpoint of each, then
/// sizes.size().
std::vector<size_t> roundStarts(const std::vector<uint64_t>& sizes, uint64_t budget,
                                size_t max_count) {
  std::vector<size_t> starts{0};
  uint64_t used = 0;
  for (size_t i = 0; i < sizes.size(); ++i) {
    if (used > 0 && (used + sizes[i] > budget || i - starts.back() >= max_count)) {
      starts.push_back(i);
      used = 0;
    }
    used += sizes[i];
  }
  starts.push_back(sizes.size());
  return starts;
}

}  // namespace

void gainReach(const GainBatch& batch, BlockKey* lo_key, BlockKey* hi_key) {
  const size_t n = batch.viewpoints();
  const int half = halfSideOf(batch);
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = hi[a] = n ? batch.origins_v[a] : 0.0;
    for (size_t i = 0; i < n; ++i) {
      lo[a] = std::min(lo[a], batch.origins_v[3 * i + a]);
      hi[a] = std::max(hi[a], batch.origins_v[3 * i + a]);
    }
  }
  const auto blockOf = [&](double v) { return static_cast<int>(std::floor(v)) >> kBlockBits; };
  *lo_key = BlockKey{blockOf(lo[0] - half), blockOf(lo[1] - half), blockOf(lo[2] - half)};
  *hi_key = BlockKey{blockOf(hi[0] + half), blockOf(hi[1] + half), blockOf(hi[2] + half)};
}

void viewpointGainsOnDevice(const DeviceLayerView& view, DeviceScratch& scratch,
                            const GainBatch& batch, const OccupancyModel& model,
                            const GainDeviceOptions& options, double* out, DeviceGainStats* stats) {
  const size_t n = batch.viewpoints();
  if (n == 0) return;
  options.validate();
  const auto t_start = std::chrono::steady_clock::now();
  const SeenBoxes boxes = seenBoxes(batch);
  const uint64_t words = boxes.words;
  if (words * 8 > kMaxSeenBytesPerViewpoint)
    throw InvalidArgument("gain range too long for the device (a viewpoint's cell bitmap of " +
                          std::to_string(words * 8 >> 20) + " MiB)");
  FRAGG_CUDA_CHECK(cudaSetDevice(scratch.device()));
  const cudaStream_t stream = static_cast<cudaStream_t>(scratch.stream());
  const size_t n_rays = batch.rays();
  double* origins = scratch.device<double>(kOrigins, 3 * n);
  double* cos_yaw = scratch.device<double>(kCos, n);
  double* sin_yaw = scratch.device<double>(kSin, n);
  double* rays = scratch.device<double>(kRays, 3 * n_rays);
  double* gains = scratch.device<double>(kGains, n);
  cuda::copyToDevice(origins, batch.origins_v.data(), 3 * n, stream);
  cuda::copyToDevice(cos_yaw, batch.cos_yaw.data(), n, stream);
  cuda::copyToDevice(sin_yaw, batch.sin_yaw.data(), n, stream);
  cuda::copyToDevice(rays, batch.rays_sensor.data(), 3 * n_rays, stream);
  int32_t* box_lo = scratch.device<int32_t>(kBoxLo, 3 * n);
  cuda::copyToDevice(box_lo, boxes.lo.data(), 3 * n, stream);
  FRAGG_CUDA_CHECK(cudaMemsetAsync(gains, 0, n * sizeof(double), stream));
  // Blocks by a dense table over the batch's reach where it is small enough: one load a block
  // instead of a hash probe.
  BlockKey reach_lo, reach_hi;
  gainReach(batch, &reach_lo, &reach_hi);
  const int32_t dense_dims[3] = {reach_hi.x - reach_lo.x + 1, reach_hi.y - reach_lo.y + 1,
                                 reach_hi.z - reach_lo.z + 1};
  const uint64_t dense_entries =
      uint64_t(dense_dims[0]) * uint64_t(dense_dims[1]) * uint64_t(dense_dims[2]);
  int32_t* dense = nullptr;
  if (dense_entries <= kMaxDenseEntries) {
    dense = scratch.device<int32_t>(kDense, dense_entries);
    cuda::launchDenseBlockTable(view, reach_lo, dense_dims, dense, stream);
  }
  uint64_t budget = options.bitmap_budget_bytes;
  if (budget == 0) {
    size_t free_bytes = 0, total_bytes = 0;
    FRAGG_CUDA_CHECK(cudaMemGetInfo(&free_bytes, &total_bytes));
    budget = std::clamp<uint64_t>(free_bytes / 4, kSeenBudgetMinBytes, kSeenBudgetMaxBytes);
  }
  // What every kernel reads of the round of viewpoints first .. first + m - 1.
  const auto roundOf = [&](size_t first, size_t m) {
    return cuda::GainRound{view,
                           model,
                           origins + 3 * first,
                           cos_yaw + first,
                           sin_yaw + first,
                           rays,
                           static_cast<uint32_t>(n_rays),
                           static_cast<uint32_t>(m),
                           batch.length_v};
  };
  auto t_walk = t_start;
  const auto tablesDone = [&](size_t rounds) {
    if (!stats) return;
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
    t_walk = std::chrono::steady_clock::now();
    stats->tables_seconds = std::chrono::duration<double>(t_walk - t_start).count();
    stats->rounds = rounds;
  };

  if (options.kernel == GainKernel::kPlain) {
    const size_t per_round = std::max<size_t>(1, std::min<size_t>(n, budget / (words * 8)));
    unsigned long long* seen = scratch.device<unsigned long long>(kSeen, per_round * words);
    tablesDone((n + per_round - 1) / per_round);
    for (size_t first = 0; first < n; first += per_round) {
      const size_t m = std::min(per_round, n - first);
      FRAGG_CUDA_CHECK(cudaMemsetAsync(seen, 0, m * words * 8, stream));
      cuda::GainKernelArgs args{roundOf(first, m),
                                box_lo + 3 * first,
                                {boxes.dims[0], boxes.dims[1], boxes.dims[2]},
                                words,
                                seen,
                                gains + first};
      if (dense) {
        args.dense = dense;
        args.dense_lo = reach_lo;
        for (int a = 0; a < 3; ++a) args.dense_dims[a] = dense_dims[a];
      }
      cuda::launchViewpointGains(args, stream);
    }
    cuda::copyToHost(out, gains, n, stream);
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
    if (stats) stats->walk_seconds = secondsSince(t_walk);
    return;
  }

  // Sized, pooled, queued: each viewpoint's box of its own size; rounds of viewpoints whose
  // bitmaps (dense) or directories (pooled) fit the budget, each laid out from its round's
  // start.
  const bool pooled = gainKernelPooled(options.kernel);
  const bool queued = gainKernelQueued(options.kernel);
  const bool deferred = gainKernelDeferred(options.kernel);
  int32_t* box_dims = scratch.device<int32_t>(kBoxDims, 3 * n);
  cuda::copyToDevice(box_dims, boxes.own_dims.data(), 3 * n, stream);
  std::vector<uint64_t> sizes(n);  // words (dense) or directory entries (pooled)
  for (size_t i = 0; i < n; ++i)
    sizes[i] = pooled ? directoryEntries(boxes, i) : ownWords(boxes, i);
  const uint64_t unit_bytes = pooled ? sizeof(uint32_t) : sizeof(uint64_t);
  const uint64_t round_budget =
      (pooled ? static_cast<uint64_t>(budget * (1.0 - kPoolShare)) : budget) / unit_bytes;
  // Fewer than 2^32 rays a round (the kernels index a round's rays in 32 bits).
  const size_t max_per_round = std::max<size_t>(1, 0xffffffffu / std::max<size_t>(1, n_rays));
  const std::vector<size_t> starts = roundStarts(sizes, round_budget, max_per_round);
  const size_t n_rounds = starts.size() - 1;
  std::vector<uint64_t> offsets(n);
  std::vector<uint64_t> round_units(n_rounds, 0);
  for (size_t r = 0; r < n_rounds; ++r)
    for (size_t i = starts[r]; i < starts[r + 1]; ++i) {
      offsets[i] = round_units[r];
      round_units[r] += sizes[i];
    }
  const uint64_t max_units = *std::max_element(round_units.begin(), round_units.end());
  // The kernels' index widths (cheap checks of the layout above): a round's rays and
  // viewpoints in 32 bits, every box at least a cell on each axis.
  for (size_t r = 0; r < n_rounds; ++r)
    if (uint64_t(starts[r + 1] - starts[r]) * n_rays > 0xffffffffu)
      throw std::logic_error("gain round of " + std::to_string(starts[r + 1] - starts[r]) +
                             " viewpoints passes 2^32 rays");
  for (const int32_t d : boxes.own_dims)
    if (d < 1) throw std::logic_error("gain viewpoint box of " + std::to_string(d) + " cells");
  uint64_t* offsets_d = scratch.device<uint64_t>(pooled ? kDirectoryOffset : kSeenOffset, n);
  cuda::copyToDevice(offsets_d, offsets.data(), n, stream);
  unsigned long long* seen = nullptr;
  uint32_t* directory = nullptr;
  unsigned long long* pool = nullptr;
  unsigned int* pool_taken = nullptr;
  uint32_t* overflow = nullptr;
  cuda::PoolOwner* pool_owner = nullptr;
  uint64_t pool_blocks = 0;
  if (pooled) {
    directory = scratch.device<uint32_t>(kDirectory, max_units);
    // The pool: what the budget leaves, but no more than a round's directories have entries
    // (a pool that large cannot run out; a small batch takes little).
    pool_blocks =
        options.pool_blocks
            ? options.pool_blocks
            : std::min<uint64_t>(static_cast<uint64_t>(budget * kPoolShare) / kPoolBitmapBytes,
                                 max_units);
    pool_blocks = std::clamp<uint64_t>(pool_blocks, 1, kPoolMaxBlocks);
    if (pool_blocks >= kPoolOverflow)  // an index + 1 must not read as kPoolOverflow/kPoolBusy
      throw std::logic_error("gain pool of " + std::to_string(pool_blocks) + " blocks");
    pool = scratch.device<unsigned long long>(kPool, pool_blocks * (kPoolBitmapBytes / 8));
    if (deferred) pool_owner = scratch.device<cuda::PoolOwner>(kPoolOwner, pool_blocks);
    pool_taken = scratch.device<unsigned int>(kPoolTaken, n_rounds);
    overflow = scratch.device<uint32_t>(kOverflow, n);
    FRAGG_CUDA_CHECK(cudaMemsetAsync(pool_taken, 0, n_rounds * sizeof(unsigned int), stream));
    FRAGG_CUDA_CHECK(cudaMemsetAsync(overflow, 0, n * sizeof(uint32_t), stream));
  } else {
    seen = scratch.device<unsigned long long>(kSeen, max_units);
  }
  unsigned long long* queue = nullptr;
  if (queued) {
    queue = scratch.device<unsigned long long>(kQueue, n_rounds);
    FRAGG_CUDA_CHECK(cudaMemsetAsync(queue, 0, n_rounds * sizeof(unsigned long long), stream));
  }
  tablesDone(n_rounds);
  for (size_t r = 0; r < n_rounds; ++r) {
    const size_t first = starts[r], m = starts[r + 1] - first;
    cuda::GainWalkArgs args{roundOf(first, m), box_lo + 3 * first, box_dims + 3 * first};
    args.gains = gains + first;
    if (pooled) {
      FRAGG_CUDA_CHECK(cudaMemsetAsync(directory, 0, round_units[r] * sizeof(uint32_t), stream));
      args.directory_offset = offsets_d + first;
      args.directory = directory;
      args.pool = pool;
      args.pool_blocks = static_cast<uint32_t>(pool_blocks);
      args.pool_taken = pool_taken + r;
      args.overflow = overflow + first;
    } else {
      FRAGG_CUDA_CHECK(cudaMemsetAsync(seen, 0, round_units[r] * sizeof(uint64_t), stream));
      args.seen_offset = offsets_d + first;
      args.seen = seen;
    }
    if (queued) {
      args.queue = queue + r;
      args.refill_lanes = options.refill_lanes;
    }
    if (dense) {
      args.dense = dense;
      args.dense_lo = reach_lo;
      for (int a = 0; a < 3; ++a) args.dense_dims[a] = dense_dims[a];
    }
    if (deferred) args.pool_owner = pool_owner;
    cuda::launchGainWalk(args, pooled, queued, deferred, stream);
  }
  cuda::copyToHost(out, gains, n, stream);
  if (!pooled) {
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
    if (stats) stats->walk_seconds = secondsSince(t_walk);
    return;
  }
  uint32_t* overflow_h = scratch.pinned<uint32_t>(kPinnedOverflow, n);
  unsigned int* taken_h = scratch.pinned<unsigned int>(kPinnedCounters, n_rounds);
  cuda::copyToHost(overflow_h, overflow, n, stream);
  cuda::copyToHost(taken_h, pool_taken, n_rounds, stream);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
  // The viewpoints of a round that ran out of pool bitmaps: computed again by the sized
  // kernel (their pooled gains missed the cells of the blocks that got none).
  GainBatch rerun;
  rerun.rays_sensor = batch.rays_sensor;
  rerun.length_v = batch.length_v;
  std::vector<size_t> rerun_index;
  for (size_t i = 0; i < n; ++i)
    if (overflow_h[i]) {
      rerun_index.push_back(i);
      for (int a = 0; a < 3; ++a) rerun.origins_v.push_back(batch.origins_v[3 * i + a]);
      rerun.cos_yaw.push_back(batch.cos_yaw[i]);
      rerun.sin_yaw.push_back(batch.sin_yaw[i]);
    }
  uint64_t wanted = 0;
  for (size_t r = 0; r < n_rounds; ++r) wanted = std::max<uint64_t>(wanted, taken_h[r]);
  if (!rerun_index.empty()) {
    std::vector<double> again(rerun_index.size());
    GainDeviceOptions sized = options;
    sized.kernel = GainKernel::kSized;
    viewpointGainsOnDevice(view, scratch, rerun, model, sized, again.data());
    for (size_t j = 0; j < rerun_index.size(); ++j) out[rerun_index[j]] = again[j];
  }
  if (stats) {
    stats->walk_seconds = secondsSince(t_walk);
    stats->pool_blocks_wanted = wanted;
    stats->pool_reruns = rerun_index.size();
  }
}

}  // namespace fragg::planning
