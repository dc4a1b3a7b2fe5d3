// Moving objects in the simulator: scripted poses (pauses, ping-pong, doors), scene files with
// movers, per-point dynamic labels that say exactly which returns come from a mover, and the
// labels written beside a dataset and read back.
#include "fragg_map/sim/movers.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/map.h"
#include "fragg_map/sim/dataset_writers.h"
#include "fragg_map/sim/depth_camera.h"
#include "fragg_map/sim/dynamic_quality.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/scene.h"
#include "sim_test_util.h"

namespace fragg::sim {
namespace {

using geometry::MeshBvh;

MoverSpec walker() {
  MoverSpec m;
  m.name = "w";
  m.waypoints_m = {{0, 0}, {10, 0}};
  m.speed_mps = 2.0;
  m.pause_s = {1.0, 3.0};
  return m;
}

TEST(SimMovers, PathMoverPausesThenWalksBackAndForth) {
  const MoverSpec m = walker();
  Eigen::Vector2d xy;
  double yaw = 0;
  m.poseAt(0.5, &xy, &yaw);  // pausing at the start
  EXPECT_NEAR(xy.x(), 0.0, 1e-12);
  m.poseAt(1.0 + 2.5, &xy, &yaw);  // 2.5 s of walking at 2 m/s
  EXPECT_NEAR(xy.x(), 5.0, 1e-9);
  EXPECT_NEAR(yaw, 0.0, 1e-12);
  m.poseAt(1.0 + 5.0 + 2.0, &xy, &yaw);  // standing 3 s at the far end
  EXPECT_NEAR(xy.x(), 10.0, 1e-9);
  m.poseAt(1.0 + 5.0 + 3.0 + 1.0, &xy, &yaw);  // walking back
  EXPECT_NEAR(xy.x(), 8.0, 1e-9);
  EXPECT_NEAR(std::abs(yaw), M_PI, 1e-9);
  m.poseAt(14.0 + 0.5, &xy, &yaw);  // a new cycle: the start pause again
  EXPECT_NEAR(xy.x(), 0.0, 1e-9);
}

TEST(SimMovers, DoorSwingsBetweenClosedAndOpen) {
  MoverSpec d;
  d.kind = MoverKind::kDoor;
  d.size_m = {1.0, 0.1, 2.0};
  d.hinge_m = {2, 3};
  d.closed_yaw_deg = 0;
  d.open_yaw_deg = 90;
  d.period_s = 4;
  Eigen::Vector2d xy;
  double yaw = 0;
  d.poseAt(0.0, &xy, &yaw);
  EXPECT_NEAR(yaw, 0.0, 1e-12);
  d.poseAt(2.0, &xy, &yaw);
  EXPECT_NEAR(yaw, M_PI / 2, 1e-12);
  d.poseAt(3.0, &xy, &yaw);
  EXPECT_NEAR(yaw, M_PI / 4, 1e-12);
  EXPECT_EQ(xy, Eigen::Vector2d(2, 3));
  // Open: the panel reaches from the hinge along +y.
  const geometry::TriangleMesh mesh = moversMeshAt({d}, 2.0, [](double, double) { return 0.0; });
  const MeshBvh bvh(mesh);
  EXPECT_TRUE(bvh.inside(Eigen::Vector3f(2.0f, 3.5f, 1.0f)));
  EXPECT_FALSE(bvh.inside(Eigen::Vector3f(2.5f, 3.0f, 1.0f)));
}

TEST(SimMovers, SceneFileReadsMoversAndRefusesBadOnes) {
  const Scene s = sceneFromJson(R"({"ground": {"extent": [-10, -10, 10, 10]},
    "movers": [{"type": "car", "path": [[-5, 0], [5, 0]], "speed": 3, "pause": 2},
               {"type": "pedestrian", "name": "p", "path": [[0, -5], [0, 5]], "repeat": "loop"},
               {"type": "door", "hinge": [1, 2], "open_yaw": 45}]})");
  ASSERT_EQ(s.movers.size(), 3u);
  EXPECT_EQ(s.movers[0].kind, MoverKind::kCar);
  EXPECT_EQ(s.movers[0].size_m, Eigen::Vector3d(4.5, 1.8, 1.5));
  EXPECT_EQ(s.movers[0].pause_s, std::vector<double>{2.0});
  EXPECT_EQ(s.movers[1].name, "p");
  EXPECT_EQ(s.movers[1].repeat, MoverRepeat::kLoop);
  EXPECT_EQ(s.movers[2].open_yaw_deg, 45.0);
  const char* bad[] = {
      R"({"ground": {"extent": [-1, -1, 1, 1]}, "movers": [{"type": "horse", "path": [[0, 0], [1, 0]]}]})",
      R"({"ground": {"extent": [-1, -1, 1, 1]}, "movers": [{"type": "car", "path": [[0, 0]]}]})",
      R"({"ground": {"extent": [-1, -1, 1, 1]}, "movers": [{"type": "car", "path": [[0, 0], [1, 0]], "speed": -1}]})",
      R"({"ground": {"extent": [-1, -1, 1, 1]}, "movers": [{"type": "car", "path": [[0, 0], [1, 0]], "pause": [1, 2, 3]}]})",
      R"({"ground": {"extent": [-1, -1, 1, 1]}, "movers": [{"type": "door", "hinge": [0, 0], "period": 0}]})"};
  for (const char* text : bad) EXPECT_THROW(sceneFromJson(text), InvalidArgument) << text;
}

// Every return is labelled by the surface it lies on: on the mover's box <=> dynamic.
TEST(SimMovers, LidarLabelsExactlyTheReturnsFromMovers) {
  const MeshBvh ground(test::flatGround(40));
  MoverSpec car;
  car.kind = MoverKind::kCar;
  car.size_m = {4.5, 1.8, 1.5};
  car.waypoints_m = {{6, -10}, {6, 10}};
  car.speed_mps = 5;
  const MeshBvh movers(moversMeshAt({car}, 2.0, [](double, double) { return 0.0; }));
  LidarSpec spec;
  spec.beams = 16;
  spec.azimuth_steps = 360;
  spec.max_range_m = 30;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0, 0, 1.8);
  std::vector<uint8_t> labels;
  const PointCloud cloud = simulateLidar(ground, spec, T, 1, 0, &movers, &labels);
  ASSERT_EQ(labels.size(), cloud.size());
  size_t dynamic = 0, returns = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points_S[i];
    if (!p.allFinite()) {
      EXPECT_EQ(labels[i], 0);
      continue;
    }
    ++returns;
    const Eigen::Vector3f p_map = (T.cast<float>() * p);
    const bool on_car = movers.withinDistance(p_map, 1e-3f);
    EXPECT_EQ(labels[i] == 1, on_car) << i;
    dynamic += labels[i];
  }
  EXPECT_GT(dynamic, 50u);
  EXPECT_LT(dynamic, returns);
  // Without movers the same rays reach the ground behind the car.
  const PointCloud without = simulateLidar(ground, spec, T, 1, 0);
  size_t behind = 0;
  for (size_t i = 0; i < cloud.size(); ++i)
    if (labels[i]) behind += without.points_S[i].allFinite() ? 1 : 0;
  EXPECT_GT(behind, 0u);
}

TEST(SimMovers, LabelsAreWrittenPerReturnedPointAndReadBack) {
  const std::string dir = test::testDir();
  const MeshBvh ground(test::flatGround(20));
  MoverSpec p = walker();
  p.waypoints_m = {{3, -1}, {3, 1}};
  const MeshBvh movers(moversMeshAt({p}, 0.0, [](double, double) { return 0.0; }));
  DepthCameraSpec spec;
  spec.width = 64;
  spec.height = 48;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0, 0, 1.0);
  Eigen::Matrix3d optical;
  optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // camera looks along +x
  T.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()).matrix() * optical;
  std::vector<uint8_t> labels;
  const PointCloud cloud = simulateDepthCamera(ground, spec, T, 1, 0, &movers, &labels);
  DepthFolderWriter writer(dir + "/depth_set", spec.intrinsics());
  writer.add(cloud, T, T, 0.0, &labels);
  writer.finish();
  const std::vector<uint8_t> back = readDynamicLabels(dir + "/depth_set", 0);
  // One label a point the reader gives back, in its order.
  auto source = openDataset(dir + "/depth_set");
  Scan scan;
  ASSERT_TRUE(source->next(scan));
  std::vector<uint8_t> expected;
  size_t k = 0;
  for (size_t i = 0; i < scan.cloud.size(); ++i)
    if (scan.cloud.points_S[i].allFinite()) {
      ++k;
      expected.push_back(labels[i]);
    }
  ASSERT_EQ(back.size(), k);
  EXPECT_EQ(back, expected);
  size_t ones = 0;
  for (uint8_t v : back) ones += v;
  EXPECT_GT(ones, 10u);
  EXPECT_THROW(readDynamicLabels(dir + "/depth_set", 1), IoError);
}

// SA, DA and ghost cells on a hand-made case: a ground slab seen from above, one floating
// "mover" point inserted (a ghost, not removed) and one dynamic point whose cell stays free.
TEST(SimDynamicQuality, CountsKeptStaticRemovedDynamicAndGhostCells) {
  const MeshBvh ground(test::flatGround(10));  // top at z = 0
  MapParams params;
  params.resolution_m = 0.1;
  params.backend = Backend::kCpu;
  Map map(params);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.05, 0.05, 2.05);
  PointCloud cloud;
  for (int x = -5; x <= 5; ++x)
    for (int y = -5; y <= 5; ++y)
      cloud.points_S.emplace_back(0.1f * x, 0.1f * y, -2.03f);  // on the ground (z = 0.02)
  cloud.points_S.emplace_back(0.3f, 0.3f, -1.0f);               // a mover's hit, in the air
  cloud.points_S.emplace_back(std::nanf(""), 0.f, 0.f);         // no return: no label
  for (int k = 0; k < 3; ++k) map.insert(cloud, T, SensorModel::autoFromCloud());
  std::vector<uint8_t> labels(121, 0);
  labels.push_back(1);
  // A second dynamic point in a cell the rays cleared (free): removed.
  PointCloud eval_cloud = cloud;
  eval_cloud.points_S.emplace_back(0.0f, 0.0f, -0.5f);
  std::vector<uint8_t> eval_labels = labels;
  eval_labels.push_back(1);
  DynamicQuality q;
  addLabelledScan(map, eval_cloud, T, eval_labels, false, q);
  countGhostCells(map, ground, false, q);
  EXPECT_EQ(q.static_points, 121u);
  EXPECT_EQ(q.static_kept, 121u);
  EXPECT_DOUBLE_EQ(q.staticAccuracy(), 1.0);
  EXPECT_EQ(q.dynamic_points, 2u);
  EXPECT_EQ(q.dynamic_removed, 1u);  // the floating hit is occupied: not removed
  EXPECT_DOUBLE_EQ(q.dynamicAccuracy(), 0.5);
  EXPECT_EQ(q.ghost_cells, 1u);  // its cell is free in the static truth
  EXPECT_GE(q.occupied, 122u);
  // A range limit leaves the far points out.
  DynamicQuality near;
  addLabelledScan(map, eval_cloud, T, eval_labels, false, near, 1.8);
  EXPECT_EQ(near.static_points, 0u);
  EXPECT_EQ(near.dynamic_points, 2u);
  // A label count other than the finite points is refused.
  eval_labels.pop_back();
  EXPECT_THROW(addLabelledScan(map, eval_cloud, T, eval_labels, false, q), InvalidArgument);
}

}  // namespace
}  // namespace fragg::sim
