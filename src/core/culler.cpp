#include "fragg_map/internal/culler.h"

#include <omp.h>

#include <algorithm>
#include <cmath>

namespace fragg {

bool Culler::sameModel(const SensorModel& m) const {
  const SensorModel& l = last_model_;
  return have_model_ && l.type == m.type && l.hfov_rad == m.hfov_rad && l.vfov_rad == m.vfov_rad &&
         l.elevation_min_rad == m.elevation_min_rad && l.elevation_max_rad == m.elevation_max_rad &&
         l.max_range_m == m.max_range_m && l.forward_S == m.forward_S && l.right_S == m.right_S;
}

void Culler::reset() {
  for (auto& h : history_) h.valid = false;
  have_model_ = false;
}

CullContext Culler::context(const Frustum& f, const Eigen::Isometry3d& T_map_sensor) const {
  CullContext ctx;
  ctx.scan = scan_;
  ctx.ttl = std::min(params_.coherence_ttl_scans, kMaxCoherenceTtl);
  ctx.plane_memory = params_.plane_memory;
  ctx.rotation_coherence = params_.rotation_coherence;
  ctx.translation_coherence = params_.translation_coherence;
  const Eigen::Vector3d o_now = T_map_sensor.translation();
  for (int k = 1; k < ctx.ttl && k < static_cast<int>(scan_); ++k) {
    const PastSensorPose& h = history_[(scan_ - k) % kMaxCoherenceTtl];
    if (!h.valid) continue;
    PastPose& p = ctx.past[k];
    const Eigen::Vector3d delta = o_now - h.T_map_sensor.translation();
    p.valid = true;
    // Rounded up a little so that float rounding can only make coherence more cautious.
    p.translation_m = static_cast<float>(delta.norm() * (1 + 1e-6) + 1e-6);
    const Eigen::AngleAxisd rot(h.T_map_sensor.linear().transpose() * T_map_sensor.linear());
    p.rotation_rad = static_cast<float>(std::fabs(rot.angle()) * (1 + 1e-6) + 1e-7);
    for (int i = 0; i < f.num_tests; ++i) {
      if (f.tests[i] != FrustumTest::kPlane) continue;
      const Eigen::Vector3d n(f.planes[i][0], f.planes[i][1], f.planes[i][2]);
      p.advance_m[i] = static_cast<float>(n.dot(delta) - 1e-6 * delta.norm() - 1e-6);
    }
  }
  return ctx;
}

CullContext Culler::beginScan(const Frustum& f, const SensorModel& model,
                              const Eigen::Isometry3d& T_map_sensor) {
  if (!sameModel(model)) {
    reset();
    last_model_ = model;
    have_model_ = true;
  }
  ++scan_;
  const CullContext ctx = context(f, T_map_sensor);
  history_[scan_ % kMaxCoherenceTtl] = {true, T_map_sensor};
  return ctx;
}

CullCounters Culler::cull(const Frustum& f, const SensorModel& model,
                          const Eigen::Isometry3d& T_map_sensor, double resolution_m,
                          BlockMap& blocks, std::vector<BlockIndex>* visible) {
  const CullContext ctx = beginScan(f, model, T_map_sensor);

  std::vector<BlockIndex> candidates;
  blocks.forEachInBox(f.aabb_min, f.aabb_max, [&](BlockIndex i) { candidates.push_back(i); });

  const double block_m = resolution_m * kBlockSize;
  const float half_m = static_cast<float>(block_m / 2);
  CullCounters total;
  std::vector<char> is_visible(candidates.size(), 0);
#pragma omp parallel
  {
    CullCounters local;
#pragma omp for schedule(static) nowait
    for (long j = 0; j < static_cast<long>(candidates.size()); ++j) {
      BlockMeta& m = blocks.meta(candidates[j]);
      float c[3];
      const int32_t k[3] = {m.key.x, m.key.y, m.key.z};
      for (int a = 0; a < 3; ++a)
        c[a] = static_cast<float>((static_cast<double>(k[a]) + 0.5) * block_m - f.origin_m[a]);
      is_visible[j] = cullBlock(f, ctx, c, half_m, m.cull, local);
    }
#pragma omp critical(fragg_cull_counters)
    total.add(local);
  }
  if (visible) {
    for (size_t j = 0; j < candidates.size(); ++j)
      if (is_visible[j]) visible->push_back(candidates[j]);
  }
  return total;
}

}  // namespace fragg
