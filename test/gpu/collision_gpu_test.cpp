// The CUDA collision checker against the CPU one: every shape (box, sphere, capsule, closed and
// open meshes), with and without unknown_is_occupied, margins and cell counts, and path mode,
// on a map built from a real scan with random poses. The answers must be identical: collides,
// colliding cell count, first colliding cell, and for paths the segment, fraction and poses
// checked. Needs a device (skips without one).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_primitives.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/planning/collision_check.h"
#include "fragg_map/planning/path_check.h"
#include "geometry/mesh_test_util.h"
#include "gpu_test_util.h"

namespace fragg::planning {
namespace {

const std::string kRoomScan = std::string(FRAGG_REAL_DATA) + "/pcl_room_scans/room_scan1.pcd";

Map buildRoomMap(Backend backend) {
  MapParams params;
  params.resolution_m = 0.05;
  params.backend = backend;
  Map m(params);
  auto source = openDataset(kRoomScan);
  Scan scan;
  while (source->next(scan)) m.insert(scan.cloud, scan.T_map_sensor, SensorModel::autoFromCloud());
  return m;
}

const Map& roomMap() {
  static const Map map = buildRoomMap(Backend::kCpu);
  return map;
}

std::vector<Eigen::Isometry3d> randomPoses(const Map& map, size_t n, uint32_t seed) {
  const KeyBounds b = map.bounds();
  const Eigen::Vector3d lo = map.centerOf(b.min), hi = map.centerOf(b.max);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uy(lo.y(), hi.y()), uz(lo.z(), hi.z()),
      u(-1.0, 1.0);
  std::vector<Eigen::Isometry3d> out(n);
  for (Eigen::Isometry3d& T : out) {
    Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
    if (q.norm() < 1e-3) q = Eigen::Quaterniond::Identity();
    T = Eigen::Isometry3d::Identity();
    T.linear() = q.normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(ux(rng), uy(rng), uz(rng));
  }
  return out;
}

struct NamedShape {
  std::string name;
  CollisionShape shape;
};

std::vector<NamedShape> shapes() {
  geometry::TriangleMesh open =
      geometry::test::boxSolid({-0.3f, -0.2f, -0.1f}, {0.3f, 0.2f, 0.25f});
  open.triangles.resize(10);  // a box missing its top: a surface only
  open.solid_of_triangle.resize(10);
  geometry::TriangleMesh two_solids =
      geometry::test::boxSolid({-0.25f, -0.1f, -0.1f}, {0.25f, 0.1f, 0.1f});
  two_solids.appendSolid(geometry::ellipsoidMesh({0.12f, 0.12f, 0.2f}, 8, 10));
  return {{"box", CollisionShape::box({0.3, 0.2, 0.15})},
          {"sphere", CollisionShape::sphere(0.22)},
          {"capsule", CollisionShape::capsule(0.12, 0.4)},
          {"closed ellipsoid mesh",
           CollisionShape::mesh(geometry::ellipsoidMesh({0.35f, 0.3f, 0.25f}, 12, 16))},
          {"two closed solids", CollisionShape::mesh(two_solids)},
          {"open mesh", CollisionShape::mesh(open)}};
}

void expectSame(const std::vector<CollisionResult>& cpu, const std::vector<CollisionResult>& gpu,
                const std::string& what, int* colliding) {
  ASSERT_EQ(cpu.size(), gpu.size()) << what;
  for (size_t i = 0; i < cpu.size(); ++i) {
    ASSERT_EQ(cpu[i].collides, gpu[i].collides) << what << " pose " << i;
    ASSERT_EQ(cpu[i].colliding_cells, gpu[i].colliding_cells) << what << " pose " << i;
    if (!cpu[i].collides) continue;
    ++*colliding;
    ASSERT_EQ(cpu[i].first_cell, gpu[i].first_cell) << what << " pose " << i;
  }
}

TEST(CollisionGpu, EveryShapeAndOptionMatchesTheCpu) {
  REQUIRE_DEVICE();
  const Map& map = roomMap();
  ASSERT_GT(map.blockCount(), 0u);
  const std::vector<Eigen::Isometry3d> poses = randomPoses(map, 3000, 7);
  for (const NamedShape& s : shapes()) {
    for (const bool unknown : {false, true})
      for (const double margin : {0.0, 0.07})
        for (const bool count : {false, true}) {
          CollisionOptions o;
          o.unknown_is_occupied = unknown;
          o.margin_m = margin;
          o.count_cells = count;
          const std::string what = s.name + (unknown ? " unknown-occupied" : "") +
                                   (margin > 0 ? " margin" : "") + (count ? " count" : "");
          const auto cpu = checkPoses(map, s.shape, poses, o, Backend::kCpu);
          const auto gpu = checkPoses(map, s.shape, poses, o, Backend::kCuda);
          int colliding = 0;
          expectSame(cpu, gpu, what, &colliding);
          std::printf("[gpu] collision %s: %d of %zu poses collide, CPU == CUDA\n", what.c_str(),
                      colliding, poses.size());
          // Both outcomes exercised (unknown space as obstacles: most poses collide).
          EXPECT_GT(colliding, 20) << what;
          if (!unknown) {
            EXPECT_LT(colliding, static_cast<int>(poses.size()) - 20) << what;
          }
        }
  }
}

// A map on the CUDA backend: the kernels read its state masks in place through the device layer
// view (Map::deviceView, the map's own scratch), nothing classified or uploaded; the answers
// equal the CPU checker's over the same map's host blocks.
TEST(CollisionGpu, DeviceLayerViewOfACudaMapMatchesTheCpu) {
  REQUIRE_DEVICE();
  const Map map = buildRoomMap(Backend::kCuda);
  ASSERT_STREQ(map.backendName(), "cuda");
  const std::vector<Eigen::Isometry3d> poses = randomPoses(map, 3000, 11);
  BlockKey lo, hi;
  {
    const KeyBounds b = map.bounds();
    lo = blockKeyOf(b.min);
    hi = blockKeyOf(b.max);
  }
  ASSERT_NE(map.deviceView(lo, hi), nullptr) << "the map's blocks fit its device";
  for (const NamedShape& s : shapes()) {
    for (const bool unknown : {false, true})
      for (const bool count : {false, true}) {
        CollisionOptions o;
        o.unknown_is_occupied = unknown;
        o.count_cells = count;
        o.margin_m = count ? 0.07 : 0.0;
        const std::string what = s.name + " (layer view)" + (unknown ? " unknown-occupied" : "") +
                                 (count ? " count margin" : "");
        const auto gpu = checkPoses(map, s.shape, poses, o, Backend::kCuda);
        const auto cpu = checkPoses(map, s.shape, poses, o, Backend::kCpu);
        int colliding = 0;
        expectSame(cpu, gpu, what, &colliding);
        std::printf("[gpu] collision %s: %d of %zu poses collide, CPU == CUDA\n", what.c_str(),
                    colliding, poses.size());
        EXPECT_GT(colliding, 20) << what;
      }
  }
}

// Poses prepared on the device (CollisionOptions::pose_preparation = kDevice: the rigid poses
// uploaded, preparePrimitivePose in the kernel): the answers equal the CPU checker's for box,
// sphere and capsule, every option, in one chunk and in many uneven ones, on a CPU map (index
// uploaded), through a CUDA map's device layer view and over a prepared map; meshes ignore the
// option and still match.
TEST(CollisionGpu, PosesPreparedOnTheDeviceMatchTheCpu) {
  REQUIRE_DEVICE();
  const Map& map = roomMap();
  const Map cuda_map = buildRoomMap(Backend::kCuda);
  const std::vector<Eigen::Isometry3d> poses = randomPoses(map, 3000, 13);
  const PreparedMap prepared(map, false);
  int cases = 0;
  for (const NamedShape& s : shapes()) {
    const bool mesh = s.shape.kind() == ShapeKind::kMesh;
    for (const bool unknown : {false, true})
      for (const double margin : {0.0, 0.07})
        for (const bool count : {false, true})
          for (const size_t chunk : {size_t{0}, size_t{700}}) {
            if (mesh && (margin > 0 || chunk > 0)) continue;  // the option is ignored: once
            CollisionOptions o;
            o.unknown_is_occupied = unknown;
            o.margin_m = margin;
            o.count_cells = count;
            const auto cpu = checkPoses(map, s.shape, poses, o, Backend::kCpu);
            // The CUDA map's own host blocks, as the layer view test compares.
            const auto cpu_of_cuda_map = checkPoses(cuda_map, s.shape, poses, o, Backend::kCpu);
            o.pose_preparation = PosePreparation::kDevice;
            o.device_chunk_poses = chunk;
            const std::string what = s.name + " device-prepared" +
                                     (unknown ? " unknown-occupied" : "") +
                                     (margin > 0 ? " margin" : "") + (count ? " count" : "") +
                                     (chunk ? " chunks of 700" : "");
            int colliding = 0;
            expectSame(cpu, checkPoses(map, s.shape, poses, o, Backend::kCuda), what, &colliding);
            int on_view = 0;
            expectSame(cpu_of_cuda_map, checkPoses(cuda_map, s.shape, poses, o, Backend::kCuda),
                       what + " (layer view)", &on_view);
            if (!unknown) {
              int on_prepared = 0;
              expectSame(cpu, checkPoses(prepared, s.shape, poses, o, Backend::kCuda),
                         what + " (prepared map)", &on_prepared);
            }
            std::printf("[gpu] collision %s: %d of %zu poses collide, CPU == CUDA\n", what.c_str(),
                        colliding, poses.size());
            EXPECT_GT(colliding, 20) << what;
            if (!unknown) {
              EXPECT_LT(colliding, static_cast<int>(poses.size()) - 20) << what;
            }
            ++cases;
          }
  }
  EXPECT_EQ(cases, 3 * 16 + 3 * 4);
}

// A pose whose cells leave the key range (see CollisionInputs.ACellRangeBeyondTheKeyRange-
// NamesThePose): refused with the same message, naming the first such pose, whether the host
// or the device prepares the poses; the checker works on afterwards.
TEST(CollisionGpu, ACellRangeBeyondTheKeyRangeIsRefusedOnBothPreparations) {
  REQUIRE_DEVICE();
  const Map& map = roomMap();
  const double x_limit_m = 2147483647.0 * map.resolution();
  Eigen::Matrix3d R;
  R.row(0) = Eigen::Vector3d(1, 1, 1) / std::sqrt(3.0);
  R.row(1) = Eigen::Vector3d(1, -1, 0) / std::sqrt(2.0);
  R.row(2) = R.row(0).cross(R.row(1));
  Eigen::Isometry3d fine = Eigen::Isometry3d::Identity();
  fine.linear() = R;
  fine.translation().x() = x_limit_m - 2.0;
  Eigen::Isometry3d bad = fine;
  bad.translation().x() = x_limit_m - 0.75;
  std::vector<Eigen::Isometry3d> many(20000, fine);
  many[15000] = bad;
  many[19000] = bad;
  const auto box = CollisionShape::box({0.01, 0.01, 0.01});
  const std::vector<Eigen::Isometry3d> good = randomPoses(map, 500, 21);
  for (const PosePreparation prep : {PosePreparation::kHost, PosePreparation::kDevice})
    for (const size_t chunk : {size_t{0}, size_t{3000}}) {
      CollisionOptions o;
      o.margin_m = 0.5;
      o.pose_preparation = prep;
      o.device_chunk_poses = chunk;
      try {
        (void)checkPoses(map, box, many, o, Backend::kCuda);
        ADD_FAILURE() << "a pose beyond the key range was accepted";
      } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("pose 15000: the shape's cells are outside the "
                                             "map's key range"),
                  std::string::npos)
            << e.what();
      }
      CollisionOptions plain;
      plain.pose_preparation = prep;
      int colliding = 0;
      expectSame(checkPoses(map, box, good, plain, Backend::kCpu),
                 checkPoses(map, box, good, plain, Backend::kCuda), "after the refusal",
                 &colliding);
    }
}

TEST(CollisionGpu, SinglePosesMatchTheCpu) {
  REQUIRE_DEVICE();
  const Map& map = roomMap();
  const std::vector<Eigen::Isometry3d> poses = randomPoses(map, 50, 8);
  const CollisionShape box = CollisionShape::box({0.2, 0.3, 0.1});
  CollisionOptions o;
  o.count_cells = true;
  for (size_t i = 0; i < poses.size(); ++i) {
    const CollisionResult cpu = checkPose(map, box, poses[i], o, Backend::kCpu);
    const CollisionResult gpu = checkPose(map, box, poses[i], o, Backend::kCuda);
    ASSERT_EQ(cpu.collides, gpu.collides) << i;
    ASSERT_EQ(cpu.colliding_cells, gpu.colliding_cells) << i;
    if (cpu.collides) {
      ASSERT_EQ(cpu.first_cell, gpu.first_cell) << i;
    }
  }
}

TEST(CollisionGpu, PreparedMapsMatchTheCpu) {
  REQUIRE_DEVICE();
  const Map& map = roomMap();
  const std::vector<Eigen::Isometry3d> poses = randomPoses(map, 2000, 9);
  for (const bool unknown : {false, true}) {
    const PreparedMap prepared(map, unknown);
    for (const NamedShape& s : shapes()) {
      CollisionOptions o;
      o.unknown_is_occupied = unknown;
      o.count_cells = true;
      const auto cpu = checkPoses(map, s.shape, poses, o, Backend::kCpu);
      const auto gpu = checkPoses(prepared, s.shape, poses, o, Backend::kCuda);
      int colliding = 0;
      expectSame(cpu, gpu, s.name + " prepared" + (unknown ? " unknown-occupied" : ""), &colliding);
      EXPECT_GT(colliding, 20) << s.name;
    }
  }
}

TEST(CollisionGpu, PathsMatchTheCpu) {
  REQUIRE_DEVICE();
  const Map& map = roomMap();
  int colliding = 0, clear = 0;
  for (const NamedShape& s : shapes()) {
    for (uint32_t seed = 0; seed < 12; ++seed) {
      // Four waypoints within a few decimetres of each other: some paths clear, some not.
      std::vector<Eigen::Isometry3d> waypoints = randomPoses(map, 4, 100 + seed);
      for (size_t k = 1; k < waypoints.size(); ++k)
        waypoints[k].translation() =
            waypoints[k - 1].translation() +
            0.3 * (waypoints[k].translation() - waypoints[k - 1].translation()).normalized();
      for (const bool unknown : {false, true}) {
        CollisionOptions o;
        o.unknown_is_occupied = unknown;
        o.count_cells = seed % 2 == 0;
        const PathResult cpu = checkPath(map, s.shape, waypoints, o, PathOptions(), Backend::kCpu);
        const PathResult gpu = checkPath(map, s.shape, waypoints, o, PathOptions(), Backend::kCuda);
        const std::string what = s.name + " path " + std::to_string(seed);
        ASSERT_EQ(cpu.collides, gpu.collides) << what;
        ASSERT_EQ(cpu.poses_checked, gpu.poses_checked) << what;
        if (!cpu.collides) {
          ++clear;
          continue;
        }
        ++colliding;
        ASSERT_EQ(cpu.first_segment, gpu.first_segment) << what;
        ASSERT_EQ(cpu.fraction, gpu.fraction) << what;
        ASSERT_EQ(cpu.hit.colliding_cells, gpu.hit.colliding_cells) << what;
        ASSERT_EQ(cpu.hit.first_cell, gpu.hit.first_cell) << what;
      }
    }
  }
  std::printf("[gpu] collision paths: %d collide, %d clear, CPU == CUDA\n", colliding, clear);
  EXPECT_GT(colliding, 5);
  EXPECT_GT(clear, 5);
}

TEST(CollisionGpu, CudaRequestedWithoutADeviceIsRefused) {
  std::string why;
  if (!cudaDeviceName(0, &why).empty()) GTEST_SKIP() << "a device is present";
  const Map& map = roomMap();
  EXPECT_THROW(checkPoses(map, CollisionShape::sphere(0.1), {Eigen::Isometry3d::Identity()},
                          CollisionOptions(), Backend::kCuda),
               InvalidArgument);
  // auto falls back to the CPU.
  EXPECT_EQ(resolveCollisionBackend(Backend::kAuto, &why), Backend::kCpu);
  EXPECT_NE(why.find("auto: CPU"), std::string::npos) << why;
}

}  // namespace
}  // namespace fragg::planning
