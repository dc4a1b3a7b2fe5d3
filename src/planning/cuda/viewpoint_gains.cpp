#include "viewpoint_gains.h"

#include <algorithm>
#include <chrono>
#include <cmath>
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

/// The walk's buffers in the scratch (device buffer ids).
enum Buffer : int { kOrigins = 200, kCos, kSin, kRays, kGains, kSeen, kBoxLo, kDense };

/// Half the side of the cube around a viewpoint's cell that holds every cell its rays enter.
int halfSideOf(const GainBatch& batch) { return static_cast<int>(std::ceil(batch.length_v)) + 2; }

/// Each viewpoint's cell bitmap box (voxel keys), all of one size.
struct SeenBoxes {
  std::vector<int32_t> lo;  ///< 3 per viewpoint
  int32_t dims[3] = {0, 0, 0};
  uint64_t words = 0;  ///< 64-bit words of one bitmap
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
      boxes.dims[a] = std::max(boxes.dims[a], static_cast<int32_t>(top - lo + 1));
    }
  }
  boxes.words =
      (uint64_t(boxes.dims[0]) * uint64_t(boxes.dims[1]) * uint64_t(boxes.dims[2]) + 63) / 64;
  return boxes;
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
                            const GainBatch& batch, const OccupancyModel& model, double* out,
                            double* tables_seconds, double* walk_seconds, size_t* rounds) {
  const size_t n = batch.viewpoints();
  if (n == 0) return;
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
  size_t free_bytes = 0, total_bytes = 0;
  FRAGG_CUDA_CHECK(cudaMemGetInfo(&free_bytes, &total_bytes));
  const uint64_t budget =
      std::clamp<uint64_t>(free_bytes / 4, kSeenBudgetMinBytes, kSeenBudgetMaxBytes);
  const size_t per_round = std::max<size_t>(1, std::min<size_t>(n, budget / (words * 8)));
  unsigned long long* seen = scratch.device<unsigned long long>(kSeen, per_round * words);
  auto t_walk = t_start;
  if (tables_seconds) {
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
    t_walk = std::chrono::steady_clock::now();
    *tables_seconds = std::chrono::duration<double>(t_walk - t_start).count();
    *rounds = (n + per_round - 1) / per_round;
  }
  for (size_t first = 0; first < n; first += per_round) {
    const size_t m = std::min(per_round, n - first);
    FRAGG_CUDA_CHECK(cudaMemsetAsync(seen, 0, m * words * 8, stream));
    cuda::GainKernelArgs args{view,
                              model,
                              origins + 3 * first,
                              cos_yaw + first,
                              sin_yaw + first,
                              rays,
                              static_cast<uint32_t>(n_rays),
                              static_cast<uint32_t>(m),
                              batch.length_v,
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
  if (walk_seconds) *walk_seconds = secondsSince(t_walk);
}

}  // namespace fragg::planning
