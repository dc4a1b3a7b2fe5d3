#include <omp.h>

#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/internal/no_return_beams.h"
#include "fragg_map/internal/prepared_scan.h"
#include "fragg_map/internal/thread_count.h"

namespace fragg {

namespace {
bool finitePoint(const Eigen::Vector3f& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

/// Direction of a no-return pixel, interpolated from the nearest valid pixels in its row.
bool interpolateDirection(const PointCloud& cloud, uint32_t row, uint32_t col,
                          Eigen::Vector3d* dir_S) {
  const uint32_t w = cloud.width;
  const uint32_t reach = std::max<uint32_t>(2, w / 8);
  const Eigen::Vector3f* line = &cloud.points_S[size_t{row} * w];
  auto valid = [&](uint32_t c) { return finitePoint(line[c]) && line[c].squaredNorm() > 0.f; };
  int left = -1, right = -1;
  for (uint32_t d = 1; d <= reach && col >= d; ++d)
    if (valid(col - d)) {
      left = static_cast<int>(col - d);
      break;
    }
  for (uint32_t d = 1; d <= reach && col + d < w; ++d)
    if (valid(col + d)) {
      right = static_cast<int>(col + d);
      break;
    }
  if (left < 0 || right < 0) return false;
  const Eigen::Vector3d a = line[left].cast<double>().normalized();
  const Eigen::Vector3d b = line[right].cast<double>().normalized();
  const double t = double(col - left) / double(right - left);
  const Eigen::Vector3d d = (1 - t) * a + t * b;
  if (d.norm() < 1e-6) return false;
  *dir_S = d.normalized();
  return true;
}
}  // namespace

RayPrepParams rayPrepParams(const Eigen::Isometry3d& T_map_sensor, const SensorModel& model,
                            bool explicit_model, const MapParams& params, PreparedScan& out) {
  RayPrepParams p;
  const Eigen::Matrix3d R = T_map_sensor.linear();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) p.R[3 * r + c] = R(r, c);
  const Eigen::Vector3d o = T_map_sensor.translation();
  p.inv_res = 1.0 / params.resolution_m;
  const Eigen::Vector3d o_v = o * p.inv_res;
  if (o_v.cwiseAbs().maxCoeff() > kMaxAbsVoxel)
    throw InvalidArgument("sensor origin is outside the map's int32 key range");
  out.ref = {static_cast<int32_t>(std::floor(o_v.x())), static_cast<int32_t>(std::floor(o_v.y())),
             static_cast<int32_t>(std::floor(o_v.z()))};
  const double ref_v[3] = {double(out.ref.x), double(out.ref.y), double(out.ref.z)};
  for (int a = 0; a < 3; ++a) {
    p.origin_m[a] = o[a];
    p.ref_v[a] = ref_v[a];
    out.start_v[a] = static_cast<float>(o_v[a] - ref_v[a]);
  }
  p.min_range_m = model.min_range_m;
  p.max_range_m = model.max_range_m;  // > 0: the model is resolved
  p.noise_m = model.range_noise_m;
  p.noise_quadratic_per_m = model.range_noise_quadratic_per_m;
  p.explicit_model = explicit_model;
  p.slack_m = static_cast<float>(1e-3 + params.resolution_m);
  p.free_cut_cell = params.free_cut_cell;
  p.octomap_keys = params.raycast == RayCast::kOctomap;
  out.octomap_keys = p.octomap_keys;
  out.resolution_m = params.resolution_m;
  out.inv_res = p.inv_res;
  for (int a = 0; a < 3; ++a) out.origin_m[a] = p.origin_f[a] = static_cast<float>(o[a]);
  return p;
}

void prepareScan(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                 const SensorModel& model, const Frustum& frustum, bool explicit_model,
                 const MapParams& params, PreparedScan& out, InsertStats& stats) {
  const RayPrepParams prep = rayPrepParams(T_map_sensor, model, explicit_model, params, out);
  const size_t n = cloud.size();
  stats.points_in += n;
  out.rays.clear();

  const int threads = threadCount(params.threads);
  std::vector<std::vector<RayEnd>> per_thread(threads);
  // Dynamic classification hands points back: each ray remembers its point.
  const bool index_points = params.dynamic.enabled;
  std::vector<std::vector<uint32_t>> per_thread_index(index_points ? threads : 0);
  out.point_index.clear();
  uint64_t invalid = 0, too_close = 0, outside = 0, hits = 0, free_only = 0, no_return = 0;
  const bool clear_no_return = params.clear_no_return_rays && cloud.organised();
#pragma omp parallel num_threads(threads) reduction(+ : invalid, too_close, outside, hits, \
                                                    free_only, no_return)
  {
    std::vector<RayEnd>& local = per_thread[omp_get_thread_num()];
    local.reserve(n / threads + 16);
    std::vector<uint32_t>* local_index =
        index_points ? &per_thread_index[omp_get_thread_num()] : nullptr;
#pragma omp for schedule(static)
    for (long i = 0; i < static_cast<long>(n); ++i) {
      const Eigen::Vector3f& p = cloud.points_S[i];
      RayEnd ray;
      if (clear_no_return && !finitePoint(p)) {
        Eigen::Vector3d dir_S;
        if (interpolateDirection(cloud, static_cast<uint32_t>(i / cloud.width),
                                 static_cast<uint32_t>(i % cloud.width), &dir_S)) {
          const double s[3] = {dir_S.x() * prep.max_range_m, dir_S.y() * prep.max_range_m,
                               dir_S.z() * prep.max_range_m};
          if (freeRayEnd(prep, s, &ray)) {
            local.push_back(ray);
            if (local_index) local_index->push_back(static_cast<uint32_t>(i));
            ++no_return;
            continue;
          }
        }
        ++invalid;
        continue;
      }
      const size_t before = local.size();
      switch (prepareRay(prep, frustum, p.x(), p.y(), p.z(), cloud.freeOnly(i), &ray)) {
        case RayPrep::kHit:
          local.push_back(ray);
          ++hits;
          break;
        case RayPrep::kFreeOnly:
          local.push_back(ray);
          ++free_only;
          break;
        case RayPrep::kInvalid:
          ++invalid;
          break;
        case RayPrep::kTooClose:
          ++too_close;
          break;
        case RayPrep::kOutside:
          ++outside;
          break;
      }
      if (local_index && local.size() != before) local_index->push_back(static_cast<uint32_t>(i));
    }
  }
  size_t total = 0;
  for (const auto& v : per_thread) total += v.size();
  out.rays.reserve(total);
  for (const auto& v : per_thread) out.rays.insert(out.rays.end(), v.begin(), v.end());
  if (index_points) {
    out.point_index.reserve(total);
    for (const auto& v : per_thread_index)
      out.point_index.insert(out.point_index.end(), v.begin(), v.end());
  }
  if (clearsBeamNoReturns(params.clear_no_return_rays, cloud, model)) {
    // An unorganised cloud's no-return beams, from the sensor's beam table, after its points.
    for (const Eigen::Vector3d& dir_S : emptyBeamDirections(cloud, model.lidar_beams)) {
      const double s[3] = {dir_S.x() * prep.max_range_m, dir_S.y() * prep.max_range_m,
                           dir_S.z() * prep.max_range_m};
      RayEnd ray;
      if (!freeRayEnd(prep, s, &ray)) continue;
      out.rays.push_back(ray);
      if (index_points) out.point_index.push_back(kNoPointIndex);
      ++no_return;
    }
  }
  stats.dropped_invalid += invalid;
  stats.dropped_min_range += too_close;
  stats.dropped_outside_frustum += outside;
  stats.rays_hit += hits;
  stats.rays_free_only += free_only;
  stats.rays_no_return += no_return;
}

}  // namespace fragg
