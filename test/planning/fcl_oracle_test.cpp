// FCL as an oracle (built only when FCL is found): the occupied cells of a map built from a real
// scan become FCL boxes; random box and (open) mesh poses are checked by FCL against each
// occupied cell near them and by fragg_map_planning. They may disagree only where FCL reports
// contact with at most 1e-6 m of penetration (touching, which is not a collision here).
#include <fcl/fcl.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "fragg_map/io/dataset.h"
#include "fragg_map/planning/collision_check.h"
#include "geometry/mesh_test_util.h"
#include "planning/collision_reference.h"

namespace fragg::planning::test {
namespace {

const std::string kRoomScan = std::string(FRAGG_REAL_DATA) + "/pcl_room_scans/room_scan1.pcd";

Map roomMap() {
  MapParams params;
  params.resolution_m = 0.1;
  Map map(params);
  auto source = openDataset(kRoomScan);
  Scan scan;
  while (source->next(scan))
    map.insert(scan.cloud, scan.T_map_sensor, SensorModel::autoFromCloud());
  return map;
}

fcl::Transform3d toFcl(const Eigen::Isometry3d& T) {
  fcl::Transform3d out = fcl::Transform3d::Identity();
  out.linear() = T.linear();
  out.translation() = T.translation();
  return out;
}

struct Oracle {
  bool collides = false;
  double max_depth_m = 0.0;  ///< deepest contact FCL reports
};

// FCL against every occupied cell within `range_m` of the pose.
Oracle fclCheck(const Map& map, const std::shared_ptr<fcl::CollisionGeometryd>& shape,
                const Eigen::Isometry3d& T, double range_m) {
  const auto cell =
      std::make_shared<fcl::Boxd>(map.resolution(), map.resolution(), map.resolution());
  fcl::CollisionObjectd shape_object(shape, toFcl(T));
  Oracle o;
  const VoxelKey lo = map.keyOf(T.translation() - Vec3::Constant(range_m));
  const VoxelKey hi = map.keyOf(T.translation() + Vec3::Constant(range_m));
  for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y)
      for (int x = lo.x; x <= hi.x; ++x) {
        if (!isObstacle(map, {x, y, z}, false)) continue;
        Eigen::Isometry3d C = Eigen::Isometry3d::Identity();
        C.translation() = map.centerOf({x, y, z});
        fcl::CollisionObjectd cell_object(cell, toFcl(C));
        fcl::CollisionRequestd request(1, true);
        fcl::CollisionResultd result;
        if (fcl::collide(&shape_object, &cell_object, request, result) == 0) continue;
        o.collides = true;
        for (size_t i = 0; i < result.numContacts(); ++i)
          o.max_depth_m = std::max(o.max_depth_m, result.getContact(i).penetration_depth);
        if (result.numContacts() == 0) o.max_depth_m = 1.0;  // no depth: count as deep
      }
  return o;
}

void compare(const Map& map, const CollisionShape& shape,
             const std::shared_ptr<fcl::CollisionGeometryd>& fcl_shape, uint32_t seed,
             const char* name, const Vec3& snap_half_m = Vec3::Zero()) {
  const KeyBounds b = map.bounds();
  std::mt19937 rng(seed);
  const Vec3 lo = map.centerOf(b.min), hi = map.centerOf(b.max);
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uy(lo.y(), hi.y()), uz(lo.z(), hi.z());
  int agree = 0, touching = 0, colliding = 0;
  const int kPoses = 1000;
  for (int i = 0; i < kPoses; ++i) {
    Eigen::Isometry3d T = randomPose(rng, 0.0);
    T.translation() = Vec3(ux(rng), uy(rng), uz(rng));
    if (snap_half_m.x() > 0 && i % 2) {
      // Axis-aligned with its faces on cell faces: every contact is a touch or a full overlap.
      const double res = map.resolution();
      T.linear().setIdentity();
      for (int k = 0; k < 3; ++k)
        T.translation()[k] = std::round(T.translation()[k] / res) * res + snap_half_m[k];
    }
    const bool ours = checkPose(map, shape, T, CollisionOptions()).collides;
    const Oracle fcl = fclCheck(map, fcl_shape, T, shape.boundingRadius() + 0.2);
    colliding += ours;
    if (ours == fcl.collides) {
      ++agree;
      continue;
    }
    // Allowed only when FCL's contact is a touch: we say free, FCL reports <= 1e-6 m depth.
    EXPECT_FALSE(ours) << name << " pose " << i << ": we collide, FCL does not";
    EXPECT_LE(fcl.max_depth_m, 1e-6) << name << " pose " << i;
    ++touching;
  }
  std::printf(
      "[fcl oracle] %s: %d of %d poses agree, %d differ within 1e-6 m of touching, "
      "%d collide\n",
      name, agree, kPoses, touching, colliding);
  EXPECT_GT(colliding, 10);
  EXPECT_LT(colliding, kPoses - 10);
}

TEST(FclOracle, BoxesOnARealScan) {
  const Map map = roomMap();
  ASSERT_GT(map.blockCount(), 0u);
  const Vec3 half(0.3, 0.15, 0.2);  // whole cells: snapped poses touch cell faces
  compare(map, CollisionShape::box(half), std::make_shared<fcl::Boxd>(2 * half), 21, "box", half);
}

TEST(FclOracle, OpenMeshOnARealScan) {
  // An open mesh (a box missing its top): a surface for FCL and for fragg_map alike.
  geometry::TriangleMesh mesh =
      geometry::test::boxSolid({-0.3f, -0.2f, -0.1f}, {0.3f, 0.2f, 0.25f});
  mesh.triangles.resize(10);
  mesh.solid_of_triangle.resize(10);
  const auto shape = CollisionShape::mesh(mesh);
  ASSERT_FALSE(shape.meshClosed());
  auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  std::vector<fcl::Vector3d> vertices;
  for (const auto& v : mesh.vertices_m) vertices.push_back(v.cast<double>());
  std::vector<fcl::Triangle> triangles;
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  model->beginModel();
  model->addSubModel(vertices, triangles);
  model->endModel();
  const Map map = roomMap();
  compare(map, shape, model, 22, "open mesh");
}

}  // namespace
}  // namespace fragg::planning::test
