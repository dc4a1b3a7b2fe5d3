// The scene both dynamic-rule tests share (dynamic_pass_through_test.cpp,
// dynamic_mapping_test.cpp): a room of 0.1 m cells seen from one sensor pose, a floor and a back
// wall, and a person who stands, leaves, walks across and stands again (kPersonY); the map
// parameters with the option on or off under one rule.
#pragma once

#include <Eigen/Geometry>

#include "fragg_map/map.h"
#include "fragg_map/map_params.h"
#include "fragg_map/point_cloud.h"

namespace fragg::test {

constexpr double kDynamicSceneRes = 0.1;

/// CPU map parameters at the scene's resolution, dynamic mapping `enabled` under `rule` with
/// `known_radius_cells`.
inline MapParams dynamicSceneParams(bool enabled, VoidSpaceRule rule, int known_radius_cells) {
  MapParams p;
  p.resolution_m = kDynamicSceneRes;
  p.backend = Backend::kCpu;
  p.threads = 2;
  p.dynamic.enabled = enabled;
  p.dynamic.known_radius_cells = known_radius_cells;
  p.dynamic.rule = rule;
  return p;
}

/// The centre of voxel (x, y, z) relative to the sensor, which sits at voxel (0, 0, 0)'s centre.
inline Eigen::Vector3f dynamicSceneCell(int x, int y, int z) {
  const double r = kDynamicSceneRes;
  return Eigen::Vector3f(float(x * r), float(y * r), float(z * r));
}

/// The sensor's pose: voxel (0, 0, 0)'s centre.
inline Eigen::Isometry3d dynamicScenePose() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d::Constant(0.5 * kDynamicSceneRes);
  return T;
}

/// A floor (z = -10) and a back wall (x = 40) in front of the sensor; `person_y` >= -12 adds a
/// standing person (a column of cells at x = 20) and one point at the edge of the observed
/// space (y = 15, beside never-observed cells), both inside space the earlier scans cleared.
/// The floor and wall points come first (kDynamicSceneStaticPoints of them).
inline PointCloud dynamicSceneCloud(int person_y) {
  PointCloud c;
  for (int x = 2; x < 40; ++x)
    for (int y = -15; y <= 15; ++y) c.points_S.push_back(dynamicSceneCell(x, y, -10));
  for (int y = -15; y <= 15; ++y)
    for (int z = -9; z <= 10; ++z) c.points_S.push_back(dynamicSceneCell(40, y, z));
  if (person_y >= -12) {
    for (int z = -9; z <= 7; ++z) c.points_S.push_back(dynamicSceneCell(20, person_y, z));
    c.points_S.push_back(dynamicSceneCell(30, 15, 2));
  }
  return c;
}

/// Static (floor and wall) points at the start of every dynamicSceneCloud.
constexpr size_t kDynamicSceneStaticPoints = 38 * 31 + 31 * 20;

/// Where the person stands at each scan: first for three scans at y = 0, before anything is
/// void (inserted as OctoMap would; when the person has left, the rays through those cells may
/// make them void); then four scans of the empty room make the space in front of the wall void;
/// then the person walks across and stands still for six scans at y = 4 (OctoMap's rule makes
/// those cells occupied, and one scan after does not clear them).
constexpr int kDynamicScenePersonY[] = {0, 0, 0, -100, -100, -100, -100, -8, -4,
                                        0, 4, 4, 4,    4,    4,    4,    8};

}  // namespace fragg::test
