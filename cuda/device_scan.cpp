#include "device_scan.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstring>

#include "fragg_map/internal/auto_sensor.h"
#include "fragg_map/internal/no_return_beams.h"
#include "kernels.h"

namespace fragg::cuda {

namespace {
double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

void DeviceScan::prepare(const ScanInput& in, const MapParams& params, int32_t free_top,
                         InsertStats& stats) {
  const auto t0 = std::chrono::steady_clock::now();
  ScanCounters& c = counters();
  c = ScanCounters{};
  for (int a = 0; a < 3; ++a) {
    c.lo_v[a] = 0;  // the start cell is part of the box
    c.hi_v[a] = 0;
  }
  c.free_top = free_top;
  // The points gatherAutoSensorStats() or stageAhead() uploaded, when they are this scan's.
  const bool staged = in.cloud_staged && staged_points_ == in.cloud.points_S.data() &&
                      staged_size_ == in.cloud.size();
  staged_points_ = nullptr;
  stats_ahead_ = false;
  if (staged && staged_ahead_) stats.scans_staged += 1;
  staged_ahead_ = false;
  if ((params.clear_no_return_rays && in.cloud.organised()) ||
      clearsBeamNoReturns(params.clear_no_return_rays, in.cloud, in.model)) {
    prepareOnHost(in, params, stats);
    stats.seconds_prepare += secondsSince(t0);
    return;
  }
  const RayPrepParams prep =
      rayPrepParams(in.T_map_sensor, in.model, in.explicit_model, params, prepared_);
  const size_t n = in.cloud.size();
  if (!staged) uploadPoints(in.cloud);
  rays_.reserve(n);
  uint32_t* ray_points = nullptr;  // MapParams::dynamic: the dynamic points come from them
  if (params.dynamic.enabled) {
    ray_points_.reserve(n);
    ray_points = ray_points_.get();
  }
  const uint8_t* free_only = nullptr;  // the device's flags, when the cloud has any
  if (in.cloud.hasFreeOnly()) {
    free_only_.reserve(n);
    std::memcpy(free_only_.host(), in.cloud.free_only.data(), n);
    free_only_.toDevice(n, stream_);
    free_only = free_only_.device();
  }
  countersToDevice();
  launchPrepare(points_.device(), free_only, uint32_t(n), prep, in.frustum, rays_.get(), ray_points,
                counters_.device(), stream_);
  countersToHost();
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
  stats.points_in += n;
  stats.rays_hit += c.hits;
  stats.rays_free_only += c.free_only;
  stats.dropped_invalid += c.invalid;
  stats.dropped_min_range += c.too_close;
  stats.dropped_outside_frustum += c.outside;
  stats.seconds_prepare += secondsSince(t0);
}

void DeviceScan::uploadPoints(const PointCloud& cloud) {
  const size_t n = cloud.size();
  staged_points_ = nullptr;
  staged_ahead_ = false;
  stats_ahead_ = false;
  if (n == 0) return;
  points_.reserve(3 * n);
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "packed points");
  const float* src = reinterpret_cast<const float*>(cloud.points_S.data());
  float* dst = points_.host();
#pragma omp parallel for schedule(static) num_threads(threads_)
  for (long chunk = 0; chunk < 64; ++chunk) {
    const size_t b = 3 * n * size_t(chunk) / 64, e = 3 * n * size_t(chunk + 1) / 64;
    std::memcpy(dst + b, src + b, (e - b) * sizeof(float));
  }
  points_.toDevice(3 * n, stream_);
}

AutoSensorStats DeviceScan::gatherAutoSensorStats(const PointCloud& cloud, bool staged_ahead) {
  const bool ready = staged_ahead && stats_ahead_ && staged_points_ == cloud.points_S.data() &&
                     staged_size_ == cloud.size();
  if (!ready) {
    uploadPoints(cloud);
    launchStats(cloud.size());
  }
  stats_ahead_ = false;
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
  staged_points_ = cloud.points_S.data();
  staged_size_ = cloud.size();
  return auto_stats_[0].stats();
}

void DeviceScan::launchStats(size_t n) {
  auto_stats_.reserve(1);
  auto_stats_[0] = AutoStatsAccum::empty();
  auto_stats_.toDevice(1, stream_);
  launchAutoSensorStats(points_.device(), uint32_t(n), sensorAxisTable(), auto_stats_.device(),
                        stream_);
  auto_stats_.toHost(1, stream_);
}

void DeviceScan::stageAhead(const PointCloud& cloud, bool auto_stats) {
  uploadPoints(cloud);
  if (cloud.size() == 0) return;
  if (auto_stats) launchStats(cloud.size());
  stats_ahead_ = auto_stats;
  staged_ahead_ = true;
  staged_points_ = cloud.points_S.data();
  staged_size_ = cloud.size();
}

void DeviceScan::prepareOnHost(const ScanInput& in, const MapParams& params, InsertStats& stats) {
  // No-return rays need the row neighbours' directions (organised) or the whole cloud's
  // beam bins (unorganised, with a beam table).
  prepareScan(in.cloud, in.T_map_sensor, in.model, in.frustum, in.explicit_model, params, prepared_,
              stats);
  ScanCounters& c = counters();
  c.rays = static_cast<uint32_t>(prepared_.rays.size());
  for (size_t i = 0; i < prepared_.rays.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      c.lo_v[a] = std::min(c.lo_v[a], prepared_.endCell(i, a));
      c.hi_v[a] = std::max(c.hi_v[a], prepared_.endCell(i, a));
    }
  rays_.reserve(c.rays);
  copyToDevice(rays_.get(), prepared_.rays.data(), c.rays, stream_);
  if (params.dynamic.enabled) {  // prepareScan listed each ray's point
    ray_points_.reserve(c.rays);
    copyToDevice(ray_points_.get(), prepared_.point_index.data(), c.rays, stream_);
  }
  countersToDevice();
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

void DeviceScan::rayBlockBox(BlockKey* lo, BlockKey* hi) const {
  const ScanCounters& c = counters();
  const int32_t ref[3] = {prepared_.ref.x, prepared_.ref.y, prepared_.ref.z};
  int32_t l[3], h[3];
  for (int a = 0; a < 3; ++a) {
    l[a] = (ref[a] + c.lo_v[a] - 1) >> kBlockBits;
    h[a] = (ref[a] + c.hi_v[a] + 1) >> kBlockBits;
  }
  *lo = {l[0], l[1], l[2]};
  *hi = {h[0], h[1], h[2]};
}

std::vector<int32_t> DeviceScan::misses(uint32_t n) const {
  n = std::min(n, missCapacity());
  misses_.toHost(n, stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
  return std::vector<int32_t>(misses_.host(), misses_.host() + n);
}

}  // namespace fragg::cuda
