#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "fragg_map/internal/culler.h"
#include "fragg_map/internal/frustum_builder.h"
#include "fragg_map/map.h"

namespace fragg {
namespace {

constexpr double kRes = 0.1;  // blocks of 0.8 m
constexpr double kDeg = M_PI / 180.0;

/// Is the block at `key` visible from a frustum (no memory)?
bool visible(const Frustum& f, const BlockKey& key) {
  const double b = kRes * kBlockSize;
  const int32_t k[3] = {key.x, key.y, key.z};
  float c[3];
  for (int a = 0; a < 3; ++a) c[a] = static_cast<float>((k[a] + 0.5) * b - f.origin_m[a]);
  CullContext ctx;
  CullMemory mem;
  CullCounters n;
  return cullBlock(f, ctx, c, static_cast<float>(b / 2), mem, n);
}

Eigen::Isometry3d pose(double x, double y, double z, double yaw_rad, double pitch_rad = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

TEST(FrustumTest, PinholeInsideOutsideAndStraddling) {
  // Body-frame camera at the origin looking along +x, 60 x 40 degrees, 10 m.
  const SensorModel cam =
      SensorModel::pinhole(60 * kDeg, 40 * kDeg, 0.0, 10.0, OpticalAxis::kXForward);
  const Frustum f = buildFrustum(cam, pose(0.0, 0.0, 0.0, 0.0), kRes);
  EXPECT_TRUE(visible(f, {5, 0, 0}));    // straight ahead at 4.4 m
  EXPECT_FALSE(visible(f, {-3, 0, 0}));  // behind
  EXPECT_FALSE(visible(f, {2, 8, 0}));   // far to the left (70 degrees)
  EXPECT_FALSE(visible(f, {20, 0, 0}));  // beyond 10 m
  // Straddles the left plane: centre just outside 30 degrees, box reaches inside.
  const double cx = 4.4, cy = std::tan(30 * kDeg) * cx + 0.3;
  EXPECT_TRUE(visible(f, {static_cast<int32_t>(std::floor(cx / 0.8)),
                          static_cast<int32_t>(std::floor(cy / 0.8)), 0}));
  // Block containing the sensor: visible.
  EXPECT_TRUE(visible(f, {0, 0, 0}));
  // Frustum AABB holds the pyramid: 10 m ahead, +-tan(30) * 10 m sideways.
  EXPECT_EQ(f.aabb_max.x, static_cast<int32_t>(std::floor(10.0 / 0.8)));
  EXPECT_EQ(f.aabb_min.x, 0);  // nothing behind the camera
  EXPECT_EQ(f.aabb_max.y, static_cast<int32_t>(std::floor(std::tan(30 * kDeg) * 10.0 / 0.8)));
}

TEST(FrustumTest, LidarShellRejectsAboveBelowAndBeyond) {
  const SensorModel lidar = SensorModel::spinningLidar(-15 * kDeg, 15 * kDeg, 0.0, 20.0);
  const Frustum f = buildFrustum(lidar, pose(0.0, 0.0, 0.0, 0.3), kRes);
  EXPECT_TRUE(visible(f, {10, 0, 0}));     // 8 m ahead at sensor height
  EXPECT_TRUE(visible(f, {-10, -10, 1}));  // behind: a LiDAR sees all around
  EXPECT_FALSE(visible(f, {2, 0, 10}));    // straight above
  EXPECT_FALSE(visible(f, {2, 0, -10}));   // straight below
  EXPECT_FALSE(visible(f, {40, 0, 0}));    // beyond 20 m
  // Bounding box: height limited by the elevation limits.
  EXPECT_LE(f.aabb_max.z, static_cast<int32_t>(std::floor(20.0 * std::sin(15 * kDeg) / 0.8)) + 1);
}

/// Fills a grid of blocks around the origin.
void fillBlocks(BlockMap& blocks, int r) {
  for (int x = -r; x <= r; ++x)
    for (int y = -r; y <= r; ++y)
      for (int z = -3; z <= 3; ++z) blocks.findOrCreate({x, y, z});
}

std::set<std::tuple<int, int, int>> keysOf(const BlockMap& blocks,
                                           const std::vector<BlockIndex>& v) {
  std::set<std::tuple<int, int, int>> s;
  for (BlockIndex i : v) {
    const BlockKey& k = blocks.meta(i).key;
    s.insert({k.x, k.y, k.z});
  }
  return s;
}

void expectSameVisibleSets(const SensorModel& model, const std::vector<Eigen::Isometry3d>& path,
                           CullCounters* saved) {
  CullingParams on, off;
  off.plane_memory = off.rotation_coherence = off.translation_coherence = false;
  Culler with(on), without(off);
  BlockMap a, b;
  fillBlocks(a, 25);
  fillBlocks(b, 25);
  for (size_t i = 0; i < path.size(); ++i) {
    const Frustum f = buildFrustum(model, path[i], kRes);
    std::vector<BlockIndex> va, vb;
    const CullCounters ca = with.cull(f, model, path[i], kRes, a, &va);
    const CullCounters cb = without.cull(f, model, path[i], kRes, b, &vb);
    ASSERT_EQ(keysOf(a, va), keysOf(b, vb)) << "scan " << i;
    EXPECT_EQ(ca.blocks_visible, cb.blocks_visible);
    EXPECT_EQ(cb.saved_by_plane_memory + cb.saved_by_rotation + cb.saved_by_translation, 0u);
    if (i > 0) {
      EXPECT_GT(ca.blocks_visible, 0u);
    }
    saved->add(ca);
  }
}

TEST(FrustumTest, CoherenceNeverChangesTheVisibleSet) {
  const SensorModel cam =
      SensorModel::pinhole(70 * kDeg, 50 * kDeg, 0.0, 12.0, OpticalAxis::kXForward);
  std::vector<Eigen::Isometry3d> path;
  for (int i = 0; i < 40; ++i)  // a camera walking forward while panning left and right
    path.push_back(pose(-4.0 + 0.1 * i, 0.05 * i, 0.2, 0.6 * std::sin(0.15 * i), 0.05));
  for (int i = 0; i < 10; ++i) path.push_back(pose(0.0, 2.0, 0.2, 2.0 + 0.02 * i));  // slow turn
  CullCounters cam_counters;
  expectSameVisibleSets(cam, path, &cam_counters);
  EXPECT_GT(cam_counters.saved_by_plane_memory, 0u);
  EXPECT_GT(cam_counters.saved_by_rotation, 0u);
  EXPECT_GT(cam_counters.saved_by_translation, 0u);

  const SensorModel lidar = SensorModel::spinningLidar(-20 * kDeg, 10 * kDeg, 0.0, 9.0);
  CullCounters lidar_counters;
  expectSameVisibleSets(lidar, path, &lidar_counters);
  EXPECT_GT(lidar_counters.saved_by_rotation, 0u);
}

/// Every valid point of `cloud` lies inside the frustum of `model` at the identity pose.
void expectCloudInside(const SensorModel& model, const PointCloud& cloud) {
  const Frustum f = buildFrustum(model, Eigen::Isometry3d::Identity(), kRes);
  for (const auto& p : cloud.points_S) {
    if (!p.allFinite()) continue;
    const float q[3] = {p.x(), p.y(), p.z()};
    ASSERT_TRUE(frustumContains(f, q, 1e-4f)) << p.transpose();
  }
}

TEST(FrustumTest, AutoSensorFollowsTheCloudsExtent) {
  // A spinning LiDAR: 360 degrees of azimuth, -25..+15 degrees of elevation.
  PointCloud lidar;
  for (int r = 0; r < 16; ++r)
    for (int k = 0; k < 360; ++k) {
      const double el = (-25.0 + 40.0 * r / 15) * kDeg, az = k * kDeg;
      lidar.points_S.emplace_back(Eigen::Vector3d(12 * std::cos(el) * std::cos(az),
                                                  12 * std::cos(el) * std::sin(az),
                                                  12 * std::sin(el))
                                      .cast<float>());
    }
  const SensorModel l = resolveAutoSensor(SensorModel::autoFromCloud(0.0, -1.0), lidar);
  EXPECT_EQ(l.type, SensorType::kSpinningLidar);
  EXPECT_LE(l.elevation_min_rad, -25 * kDeg);
  EXPECT_GE(l.elevation_max_rad, 15 * kDeg);
  EXPECT_LE(l.elevation_max_rad, 17 * kDeg);  // tight: a degree of slack, rounded
  EXPECT_GE(l.max_range_m, 12.0);             // the farthest point, rounded up to whole metres
  EXPECT_LE(l.max_range_m, 13.0);
  expectCloudInside(l, lidar);

  // A depth camera (optical frame, z forward) with a 58 x 45 degree view.
  PointCloud cam;
  for (int v = 0; v < 30; ++v)
    for (int u = 0; u < 40; ++u) {
      const double x = std::tan(29 * kDeg) * (2.0 * u / 39 - 1);
      const double y = std::tan(22.5 * kDeg) * (2.0 * v / 29 - 1);
      cam.points_S.emplace_back(Eigen::Vector3d(x, y, 1.0).cast<float>() * 3.0f);
    }
  const SensorModel c = resolveAutoSensor(SensorModel::autoFromCloud(0.0, 8.0), cam);
  EXPECT_EQ(c.type, SensorType::kPinhole);
  EXPECT_EQ(c.forward_S, Eigen::Vector3d::UnitZ());
  EXPECT_GE(c.hfov_rad, 58 * kDeg);
  EXPECT_LE(c.hfov_rad, 62 * kDeg);
  EXPECT_GE(c.vfov_rad, 45 * kDeg);
  EXPECT_LE(c.vfov_rad, 49 * kDeg);
  EXPECT_EQ(c.max_range_m, 8.0);
  expectCloudInside(c, cam);
  // The same cloud twice resolves to the same model (so coherence can carry over).
  const SensorModel again = resolveAutoSensor(SensorModel::autoFromCloud(0.0, 8.0), cam);
  EXPECT_EQ(again.hfov_rad, c.hfov_rad);
  EXPECT_EQ(again.vfov_rad, c.vfov_rad);
}

/// A camera cloud: a 58 x 45 degree view of points at ranges 1-4 m around +z, some invalid,
/// turned by `R` into the sensor frame.
PointCloud cameraCloud(const Eigen::Matrix3d& R, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  PointCloud cam;
  for (int i = 0; i < 5000; ++i) {
    const double x = std::tan(29 * kDeg) * (2 * u01(rng) - 1);
    const double y = std::tan(22.5 * kDeg) * (2 * u01(rng) - 1);
    const double depth = 1.0 + 3.0 * u01(rng);
    if (i % 97 == 0) {
      cam.points_S.emplace_back(std::nanf(""), 0.f, 1.f);
      continue;
    }
    cam.points_S.emplace_back((R * Eigen::Vector3d(x, y, 1.0) * depth).cast<float>());
  }
  return cam;
}

/// The pinhole fit around `axis` as a plain second pass over the points (dot products with the
/// model's basis), the reference for the fits the resolver gathers in its first pass.
void referenceFov(const PointCloud& cloud, const SensorModel& m, double* hfov, double* vfov) {
  const Eigen::Vector3d axis = m.forward_S, right = m.right_S, vertical = axis.cross(right);
  double tan_h = 0, tan_v = 0;
  for (const Eigen::Vector3f& p : cloud.points_S) {
    if (!p.allFinite() || p.squaredNorm() == 0.f) continue;
    const Eigen::Vector3d d = p.cast<double>();
    const double z = d.dot(axis);
    ASSERT_GT(z, std::cos(85 * kDeg) * d.norm());
    tan_h = std::max(tan_h, std::fabs(d.dot(right)) / z);
    tan_v = std::max(tan_v, std::fabs(d.dot(vertical)) / z);
  }
  *hfov = std::ceil((2 * std::atan(tan_h) + 2 * kDeg) / kDeg - 1e-9) * kDeg;
  *vfov = std::ceil((2 * std::atan(tan_v) + 2 * kDeg) / kDeg - 1e-9) * kDeg;
}

TEST(FrustumTest, AutoSensorFitsCamerasAlongEverySensorAxisAndBetween) {
  // Cameras looking along each of the six sensor axes (the resolver's one-pass fits) and along
  // axes more than 15 degrees from any (its second pass, around the mean direction): the same
  // fields of view as a plain pass of dot products with the resolved basis, to the bit, and
  // every point inside.
  const Eigen::Vector3d fwd[] = {Eigen::Vector3d::UnitX(),    -Eigen::Vector3d::UnitX(),
                                 Eigen::Vector3d::UnitY(),    -Eigen::Vector3d::UnitY(),
                                 Eigen::Vector3d::UnitZ(),    -Eigen::Vector3d::UnitZ(),
                                 Eigen::Vector3d(1, 0.45, 0), Eigen::Vector3d(0.3, -0.35, 1)};
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d axis = fwd[k].normalized();
    const Eigen::Matrix3d R =
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis).toRotationMatrix();
    const PointCloud cam = cameraCloud(R, 100 + k);
    const SensorModel m = resolveAutoSensor(SensorModel::autoFromCloud(0.0, 8.0), cam);
    ASSERT_EQ(m.type, SensorType::kPinhole) << k;
    if (k < 6)
      EXPECT_EQ(m.forward_S, axis) << k;  // snapped
    else
      EXPECT_GT(m.forward_S.dot(axis), std::cos(2 * kDeg)) << k;
    double hfov, vfov;
    referenceFov(cam, m, &hfov, &vfov);
    EXPECT_EQ(m.hfov_rad, hfov) << k;
    EXPECT_EQ(m.vfov_rad, vfov) << k;
    // 58 x 45 degrees, or 45 x 58 when the basis turned the image (+ slack and rounding; an
    // axis that does not snap is the points' mean direction, a few degrees off the camera's).
    EXPECT_LE(std::max(m.hfov_rad, m.vfov_rad), (k < 6 ? 64 : 72) * kDeg) << k;
    EXPECT_GE(std::min(m.hfov_rad, m.vfov_rad), 45 * kDeg) << k;
    expectCloudInside(m, cam);
  }
}

TEST(FrustumTest, AutoSensorKeepsTheCameraAxisWhenInvalidPixelsPullTheMeanAside) {
  // A camera cloud in its own frame (+z forward) whose upper 40 % of pixels returned nothing
  // (sky, beyond range): the mean direction is several degrees below +z, but every point fits
  // in a pyramid around +z, which is the camera's own (the one-pass fit, no second pass) and
  // no wider than the view. Turned 30 degrees, the same cloud gets its mean direction.
  PointCloud cam = cameraCloud(Eigen::Matrix3d::Identity(), 7);
  for (Eigen::Vector3f& p : cam.points_S)
    if (p.allFinite() && p.y() < -0.2f * std::tan(22.5 * kDeg) * p.z())
      p.setConstant(std::nanf(""));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3f& p : cam.points_S)
    if (p.allFinite()) mean += p.cast<double>().normalized();
  const double off_deg = std::acos(mean.normalized().z()) / kDeg;
  EXPECT_GT(off_deg, 3.0);  // the old 3-degree snap would have missed it
  EXPECT_LT(off_deg, 15.0);
  const SensorModel m = resolveAutoSensor(SensorModel::autoFromCloud(0.0, 8.0), cam);
  ASSERT_EQ(m.type, SensorType::kPinhole);
  EXPECT_EQ(m.forward_S, Eigen::Vector3d::UnitZ());
  double hfov, vfov;
  referenceFov(cam, m, &hfov, &vfov);
  EXPECT_EQ(m.hfov_rad, hfov);
  EXPECT_EQ(m.vfov_rad, vfov);
  EXPECT_LE(m.hfov_rad, 61 * kDeg);  // 58 degrees + slack and rounding
  EXPECT_LE(m.vfov_rad, 48 * kDeg);  // 45 degrees: the upper part is just empty
  expectCloudInside(m, cam);

  const Eigen::Matrix3d R(Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitY()));
  PointCloud turned = cam;
  for (Eigen::Vector3f& p : turned.points_S)
    if (p.allFinite()) p = (R * p.cast<double>()).cast<float>();
  const SensorModel t = resolveAutoSensor(SensorModel::autoFromCloud(0.0, 8.0), turned);
  ASSERT_EQ(t.type, SensorType::kPinhole);
  EXPECT_LT(t.forward_S.dot(Eigen::Vector3d::UnitZ()), std::cos(15 * kDeg));
  expectCloudInside(t, turned);
}

TEST(FrustumTest, VoxelEstimateFollowsThePaperFormula) {
  // x = 0: a cone of depth D with base pi/4 (tan(fov/2) D)^2 -> V = D/3 * S2.
  const double fov = 60 * kDeg, D = 10.0, r = 0.1;
  const double s2 = M_PI / 4 * std::pow(std::tan(fov / 2) * D, 2);
  EXPECT_NEAR(frustumVoxelEstimate(fov, D, 0.0, r), D / 3 * s2 / (r * r * r), 1e-6);
}

}  // namespace
}  // namespace fragg
