#include "fragg_map/planning/path_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "fragg_map/errors.h"

namespace fragg::planning {

namespace {
struct PathPose {
  int64_t segment;
  double fraction;
  Eigen::Isometry3d T_map_shape;
};

Eigen::Isometry3d interpolate(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s) {
  const Eigen::Quaterniond qa(a.linear()), qb(b.linear());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = qa.slerp(s, qb).normalized().toRotationMatrix();
  T.translation() = (1.0 - s) * a.translation() + s * b.translation();
  return T;
}

// The poses of segment i after its start (fractions k / n, k = 1..n).
void appendSegment(const std::vector<Eigen::Isometry3d>& w, int64_t i, double step_m,
                   double step_rad, std::vector<PathPose>* out) {
  const Eigen::Isometry3d &a = w[i], &b = w[i + 1];
  const double dist_m = (b.translation() - a.translation()).norm();
  const double angle_rad =
      Eigen::Quaterniond(a.linear()).angularDistance(Eigen::Quaterniond(b.linear()));
  const double n = std::max({1.0, std::ceil(dist_m / step_m), std::ceil(angle_rad / step_rad)});
  if (n > 1e8)
    throw InvalidArgument(
        fmt::format("path segment {} needs {} poses (too long for the step)", i, n));
  const int64_t steps = static_cast<int64_t>(n);
  for (int64_t k = 1; k <= steps; ++k) {
    const double s = double(k) / double(steps);
    out->push_back({i, s, k == steps ? b : interpolate(a, b, s)});
  }
}
}  // namespace

PathResult checkPath(const Map& map, const CollisionShape& shape,
                     const std::vector<Eigen::Isometry3d>& waypoints_T_map_shape,
                     const CollisionOptions& options, const PathOptions& path, Backend backend) {
  const auto& w = waypoints_T_map_shape;
  if (w.empty()) throw InvalidArgument("a path needs at least one waypoint");
  validate(options);
  for (const Eigen::Isometry3d& T : w) validatePose(T);
  const double step_m =
      path.max_translation_step_m > 0.0 ? path.max_translation_step_m : 0.5 * map.resolution();
  if (!std::isfinite(step_m) || !std::isfinite(path.max_rotation_step_rad) ||
      path.max_rotation_step_rad <= 0.0)
    throw InvalidArgument("path steps must be finite, the rotation step > 0");

  const Backend use = resolveCollisionBackend(backend);  // once, not per chunk
  CollisionOptions first_only = options;
  first_only.count_cells = false;
  PathResult result;
  // Segments are expanded a few at a time, checked in parallel, the earliest hit wins.
  const size_t kChunkPoses = 4096;
  std::vector<PathPose> poses;
  poses.push_back({0, 0.0, w[0]});
  int64_t next_segment = 0;
  const int64_t segments = static_cast<int64_t>(w.size()) - 1;
  for (;;) {
    while (next_segment < segments && poses.size() < kChunkPoses)
      appendSegment(w, next_segment++, step_m, path.max_rotation_step_rad, &poses);
    if (poses.empty()) break;
    std::vector<Eigen::Isometry3d> Ts(poses.size());
    for (size_t i = 0; i < poses.size(); ++i) Ts[i] = poses[i].T_map_shape;
    const std::vector<CollisionResult> r = checkPoses(map, shape, Ts, first_only, use);
    result.poses_checked += poses.size();
    for (size_t i = 0; i < r.size(); ++i) {
      if (!r[i].collides) continue;
      result.collides = true;
      result.first_segment = poses[i].segment;
      result.fraction = poses[i].fraction;
      result.T_map_shape_hit = poses[i].T_map_shape;
      result.hit = options.count_cells ? checkPose(map, shape, Ts[i], options, use) : r[i];
      result.poses_checked -= r.size() - i - 1;
      return result;
    }
    poses.clear();
  }
  return result;
}

}  // namespace fragg::planning
