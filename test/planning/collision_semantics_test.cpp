// Collision semantics on hand-set cells: touching is not colliding, unknown cells (blocks or
// not), margins, cells inside a closed mesh, path interpolation, refused inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "fragg_map/errors.h"
#include "fragg_map/planning/collision_check.h"
#include "fragg_map/planning/path_check.h"
#include "fragg_map/planning/waypoint_file.h"
#include "geometry/mesh_test_util.h"
#include "test_dir.h"

namespace fragg::planning {
namespace {

const Cell kOccupied{1, 3000};
const Cell kFree{0, -2000};

Map mapWith(const std::vector<VoxelKey>& occupied, double resolution_m = 0.1) {
  MapParams params;
  params.resolution_m = resolution_m;
  Map map(params);
  map.writeCells([&](CellWriter& w) {
    for (const VoxelKey& k : occupied) w.set(k, kOccupied);
  });
  return map;
}

Eigen::Isometry3d at(double x, double y, double z, double yaw_rad = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

bool collides(const Map& map, const CollisionShape& s, const Eigen::Isometry3d& T,
              const CollisionOptions& o = CollisionOptions()) {
  return checkPose(map, s, T, o).collides;
}

// Cell (0, 0, 0) is the cube [0, 0.1]^3.
TEST(CollisionSemantics, TouchingFacesEdgesAndCornersDoesNotCollide) {
  const Map map = mapWith({{0, 0, 0}});
  const auto box = CollisionShape::box({0.05, 0.05, 0.05});
  EXPECT_FALSE(collides(map, box, at(-0.05, 0.05, 0.05)));        // face x = 0
  EXPECT_FALSE(collides(map, box, at(0.15, 0.05, 0.05)));         // face x = 0.1
  EXPECT_FALSE(collides(map, box, at(0.05, 0.05, 0.15)));         // face z = 0.1
  EXPECT_FALSE(collides(map, box, at(-0.05, -0.05, 0.05)));       // edge
  EXPECT_FALSE(collides(map, box, at(-0.05, -0.05, -0.05)));      // corner
  EXPECT_TRUE(collides(map, box, at(-0.05 + 1e-5, 0.05, 0.05)));  // 10 um in
  EXPECT_TRUE(collides(map, box, at(0.05, 0.05, 0.05)));

  const auto sphere = CollisionShape::sphere(0.05);
  EXPECT_FALSE(collides(map, sphere, at(-0.05, 0.05, 0.05)));
  EXPECT_FALSE(collides(map, sphere, at(0.05, 0.05, 0.15)));
  EXPECT_TRUE(collides(map, sphere, at(-0.05 + 1e-5, 0.05, 0.05)));
  // Near a corner: the sphere reaches it only when its radius exceeds the distance.
  const double d = std::sqrt(3.0) * 0.05;
  EXPECT_FALSE(collides(map, CollisionShape::sphere(d), at(-0.05, -0.05, -0.05)));
  EXPECT_TRUE(collides(map, CollisionShape::sphere(d + 1e-5), at(-0.05, -0.05, -0.05)));

  // Capsule along z lying against the face y = 0 over its whole length.
  const auto capsule = CollisionShape::capsule(0.05, 0.3);
  EXPECT_FALSE(collides(map, capsule, at(0.05, -0.05, 0.05)));
  EXPECT_TRUE(collides(map, capsule, at(0.05, -0.05 + 1e-5, 0.05)));
  // Its cap touching the face z = 0 from below.
  EXPECT_FALSE(collides(map, capsule, at(0.05, 0.05, -0.2)));
  EXPECT_TRUE(collides(map, capsule, at(0.05, 0.05, -0.2 + 1e-5)));

  const auto mesh = CollisionShape::mesh(
      geometry::test::boxSolid({-0.05f, -0.05f, -0.05f}, {0.05f, 0.05f, 0.05f}));
  EXPECT_FALSE(collides(map, mesh, at(-0.05, 0.05, 0.05)));
  EXPECT_TRUE(collides(map, mesh, at(-0.04, 0.05, 0.05)));
}

TEST(CollisionSemantics, UnknownCellsWithAndWithoutBlocks) {
  MapParams params;
  params.resolution_m = 0.1;
  Map map(params);
  const auto sphere = CollisionShape::sphere(0.2);
  CollisionOptions unknown;
  unknown.unknown_is_occupied = true;
  unknown.count_cells = true;
  // An empty map: no block anywhere, every cell unknown.
  EXPECT_FALSE(collides(map, sphere, at(3, 3, 3)));
  EXPECT_TRUE(collides(map, sphere, at(3, 3, 3), unknown));
  // One block all free: the sphere inside it is clear; moved across into blockless space it is
  // not.
  map.writeCells([&](CellWriter& w) {
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) w.set({x, y, z}, kFree);
  });
  EXPECT_FALSE(collides(map, sphere, at(0.4, 0.4, 0.4), unknown));
  const CollisionResult r = checkPose(map, sphere, at(0.75, 0.4, 0.4), unknown);
  EXPECT_TRUE(r.collides);
  EXPECT_GE(r.first_cell.x, 8);  // the cells past the block
  // An unknown-band cell inside the block counts too.
  map.writeCells([&](CellWriter& w) { w.set({4, 4, 4}, Cell{0, 0}); });
  EXPECT_TRUE(collides(map, sphere, at(0.45, 0.45, 0.45), unknown));
  EXPECT_FALSE(collides(map, sphere, at(0.45, 0.45, 0.45)));
}

TEST(CollisionSemantics, MarginGrowsTheShape) {
  const Map map = mapWith({{0, 0, 0}});
  CollisionOptions margin;
  margin.margin_m = 0.1;
  // 0.05 m gap to the face x = 0.
  EXPECT_FALSE(collides(map, CollisionShape::sphere(0.05), at(-0.1, 0.05, 0.05)));
  EXPECT_TRUE(collides(map, CollisionShape::sphere(0.05), at(-0.1, 0.05, 0.05), margin));
  EXPECT_TRUE(collides(map, CollisionShape::box({0.05, 0.05, 0.05}), at(-0.1, 0.05, 0.05), margin));
  EXPECT_TRUE(collides(map, CollisionShape::capsule(0.05, 0.2), at(-0.1, 0.05, 0.05), margin));
  const auto mesh = CollisionShape::mesh(
      geometry::test::boxSolid({-0.05f, -0.05f, -0.05f}, {0.05f, 0.05f, 0.05f}));
  EXPECT_FALSE(collides(map, mesh, at(-0.1, 0.05, 0.05)));
  EXPECT_TRUE(collides(map, mesh, at(-0.1, 0.05, 0.05), margin));
  // Exactly at the margin: touching again.
  margin.margin_m = 0.05;
  EXPECT_FALSE(collides(map, CollisionShape::sphere(0.05), at(-0.1, 0.05, 0.05), margin));
}

TEST(CollisionSemantics, CellsInsideAClosedMeshCollide) {
  const Map map = mapWith({{0, 0, 0}});
  // A cube mesh whose faces are 0.3 m from the occupied cell: no triangle reaches it.
  const auto cube = geometry::test::boxSolid({-0.35f, -0.35f, -0.35f}, {0.35f, 0.35f, 0.35f});
  const auto closed = CollisionShape::mesh(cube);
  ASSERT_TRUE(closed.meshClosed());
  CollisionOptions count;
  count.count_cells = true;
  const CollisionResult r = checkPose(map, closed, at(0.05, 0.05, 0.05), count);
  EXPECT_TRUE(r.collides);
  EXPECT_EQ(r.colliding_cells, 1u);
  EXPECT_EQ(r.first_cell, (VoxelKey{0, 0, 0}));
  // Without its top face the mesh is open: a surface, which does not reach the cell.
  geometry::TriangleMesh open = cube;
  open.triangles.resize(10);
  open.solid_of_triangle.resize(10);
  const auto surface = CollisionShape::mesh(open);
  EXPECT_FALSE(surface.meshClosed());
  EXPECT_FALSE(collides(map, surface, at(0.05, 0.05, 0.05)));
  // With unknown cells occupied, the whole inside of the closed cube collides (7^3 cells).
  CollisionOptions unknown = count;
  unknown.unknown_is_occupied = true;
  EXPECT_EQ(checkPose(mapWith({}), closed, at(0.05, 0.05, 0.05), unknown).colliding_cells,
            7u * 7u * 7u);
}

TEST(CollisionPath, CatchesAThinWallBetweenFreeWaypoints) {
  std::vector<VoxelKey> wall;
  for (int z = -5; z <= 5; ++z)
    for (int y = -5; y <= 5; ++y) wall.push_back({10, y, z});  // x in [1.0, 1.1]
  const Map map = mapWith(wall);
  const auto sphere = CollisionShape::sphere(0.04);
  const std::vector<Eigen::Isometry3d> waypoints = {at(0.2, 0.05, 0.05), at(0.5, 0.05, 0.05),
                                                    at(1.6, 0.05, 0.05)};
  for (const auto& r : checkPoses(map, sphere, waypoints, CollisionOptions()))
    EXPECT_FALSE(r.collides);
  const PathResult p = checkPath(map, sphere, waypoints, CollisionOptions());
  ASSERT_TRUE(p.collides);
  EXPECT_EQ(p.first_segment, 1);
  // The sphere reaches x = 1.0 when its centre passes 0.96: fraction (0.96 - 0.5) / 1.1, found
  // within one step (half a voxel, 0.05 m, of 1.1 m).
  EXPECT_GE(p.fraction, (0.96 - 0.5) / 1.1 - 1e-9);
  EXPECT_LE(p.fraction, (0.96 - 0.5 + 0.05) / 1.1 + 1e-9);
  EXPECT_EQ(p.hit.first_cell.x, 10);
  EXPECT_TRUE(p.T_map_shape_hit.translation().x() > 0.96);
  // Stopping before the wall: clear.
  EXPECT_FALSE(checkPath(map, sphere, {at(0.2, 0, 0), at(0.9, 0, 0)}, CollisionOptions()).collides);
}

TEST(CollisionPath, RotationInPlaceSweepsThroughACell) {
  // A 1 m long stick turning 90 degrees about z at the origin passes the cell at 45 degrees.
  const Map map = mapWith({{3, 3, 0}});  // [0.3, 0.4]^2
  const auto stick = CollisionShape::box({0.5, 0.01, 0.01});
  const std::vector<Eigen::Isometry3d> waypoints = {at(0, 0, 0.05, 0.0), at(0, 0, 0.05, M_PI / 2)};
  EXPECT_FALSE(collides(map, stick, waypoints[0]));
  EXPECT_FALSE(collides(map, stick, waypoints[1]));
  const PathResult p = checkPath(map, stick, waypoints, CollisionOptions());
  ASSERT_TRUE(p.collides);
  EXPECT_EQ(p.first_segment, 0);
  EXPECT_GT(p.fraction, 0.3);
  EXPECT_LT(p.fraction, 0.7);
  EXPECT_GE(p.poses_checked, 2u);
  // One waypoint: the path is that pose.
  const PathResult single = checkPath(map, stick, {at(0.35, 0.35, 0.05)}, CollisionOptions());
  EXPECT_TRUE(single.collides);
  EXPECT_EQ(single.first_segment, 0);
  EXPECT_EQ(single.fraction, 0.0);
}

TEST(CollisionInputs, BadShapesOptionsAndPosesAreRefused) {
  EXPECT_THROW(CollisionShape::box({0.1, -0.1, 0.1}), InvalidArgument);
  EXPECT_THROW(CollisionShape::sphere(0.0), InvalidArgument);
  EXPECT_THROW(CollisionShape::capsule(NAN, 0.1), InvalidArgument);
  EXPECT_THROW(CollisionShape::capsule(0.1, -0.1), InvalidArgument);
  EXPECT_THROW(CollisionShape::mesh(geometry::TriangleMesh()), InvalidArgument);
  geometry::TriangleMesh flat;
  flat.addTriangle({0, 0, 0}, {1, 1, 1}, {2, 2, 2}, 0);  // collinear: no area
  EXPECT_THROW(CollisionShape::mesh(flat), InvalidArgument);
  const auto cube = geometry::test::boxSolid({0, 0, 0}, {1, 1, 1});
  EXPECT_THROW(CollisionShape::mesh(cube, 0.0), InvalidArgument);
  EXPECT_THROW(CollisionShape::mesh(cube, INFINITY), InvalidArgument);

  const Map map = mapWith({{0, 0, 0}});
  const auto sphere = CollisionShape::sphere(0.1);
  CollisionOptions bad;
  bad.margin_m = -0.1;
  EXPECT_THROW(checkPose(map, sphere, at(0, 0, 0), bad), InvalidArgument);
  EXPECT_THROW(checkPose(map, sphere, at(NAN, 0, 0), CollisionOptions()), InvalidArgument);
  Eigen::Isometry3d sheared = at(0, 0, 0);
  sheared.linear()(0, 1) = 0.2;
  EXPECT_THROW(checkPose(map, sphere, sheared, CollisionOptions()), InvalidArgument);
  EXPECT_THROW(checkPoses(map, sphere, {at(0, 0, 0), sheared}, CollisionOptions()),
               InvalidArgument);
  EXPECT_THROW(checkPath(map, sphere, {}, CollisionOptions()), InvalidArgument);

  // A large batch is validated on several threads: the first bad pose by index is the one
  // named (the shear at 7,000, not the NaN at 9,000), whatever the threads.
  std::vector<Eigen::Isometry3d> many(10000, at(0, 0, 0));
  many[9000] = at(NAN, 0, 0);
  many[7000] = sheared;
  for (const int threads : {1, 4}) {
    CollisionOptions o;
    o.threads = threads;
    try {
      (void)checkPoses(map, sphere, many, o);
      ADD_FAILURE() << "a batch with bad poses was accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("pose 7000: shape pose rotation is not a rotation"),
                std::string::npos)
          << e.what();
    }
  }
}

// A box whose map-frame box reaches further along x than the batch's block range allows for
// (its bounding sphere plus one margin): the rotation's first row is (1, 1, 1) / sqrt(3), so
// a 2 cm cube grown by a 0.5 m margin spans 0.03 / sqrt(3) + 0.5 sqrt(3) = 0.883 m from its
// centre along x, against a reach of 0.017 + 0.5 + 0.1 = 0.617 m. Placed 0.75 m below the
// largest x of the key range, the batch's range fits and this pose's cells do not: refused
// with the pose named, on every thread count, not a crash.
TEST(CollisionInputs, ACellRangeBeyondTheKeyRangeNamesThePose) {
  const Map map = mapWith({{0, 0, 0}});
  const double x_limit_m = 2147483647.0 * map.resolution();
  Eigen::Matrix3d R;
  R.row(0) = Eigen::Vector3d(1, 1, 1) / std::sqrt(3.0);
  R.row(1) = Eigen::Vector3d(1, -1, 0) / std::sqrt(2.0);
  R.row(2) = R.row(0).cross(R.row(1));
  Eigen::Isometry3d bad = at(x_limit_m - 0.75, 0, 0);
  bad.linear() = R;
  Eigen::Isometry3d fine = bad;
  fine.translation().x() = x_limit_m - 2.0;
  CollisionOptions o;
  o.margin_m = 0.5;
  const auto box = CollisionShape::box({0.01, 0.01, 0.01});
  EXPECT_FALSE(checkPoses(map, box, {fine, fine}, o)[1].collides);
  std::vector<Eigen::Isometry3d> many(20000, fine);
  many[15000] = bad;
  many[19000] = bad;
  for (const int threads : {1, 2}) {
    o.threads = threads;
    try {
      (void)checkPoses(map, box, many, o);
      ADD_FAILURE() << "a pose beyond the key range was accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("pose 15000: the shape's cells are outside the map's "
                                           "key range"),
                std::string::npos)
          << e.what();
    }
  }
  // The map is untouched: a good batch after it answers as before.
  EXPECT_TRUE(checkPoses(map, box, {at(0.05, 0.05, 0.05)}, CollisionOptions())[0].collides);
}

TEST(CollisionInputs, PreparedMapRefusesAChangedMapAndOtherOptions) {
  MapParams params;
  params.resolution_m = 0.1;
  Map map(params);
  map.writeCells([](CellWriter& w) { w.set({0, 0, 0}, Cell{1, 3000}); });
  const PreparedMap prepared(map, false);
  const CollisionShape sphere = CollisionShape::sphere(0.2);
  const std::vector<Eigen::Isometry3d> at_origin(1, Eigen::Isometry3d::Identity());
  EXPECT_TRUE(checkPoses(prepared, sphere, at_origin, CollisionOptions())[0].collides);
  CollisionOptions unknown;
  unknown.unknown_is_occupied = true;
  EXPECT_THROW(checkPoses(prepared, sphere, at_origin, unknown), InvalidArgument);
  map.writeCells([](CellWriter& w) { w.set({0, 0, 0}, Cell{0, -3000}); });  // now free
  EXPECT_THROW(checkPoses(prepared, sphere, at_origin, CollisionOptions()), InvalidArgument);
  EXPECT_FALSE(
      checkPoses(PreparedMap(map, false), sphere, at_origin, CollisionOptions())[0].collides);
}

TEST(CollisionInputs, WaypointLines) {
  const Eigen::Isometry3d T = parseWaypoint("1 2 3 0 0 0.7071067811865476 0.7071067811865476");
  EXPECT_NEAR(T.translation().y(), 2.0, 0);
  EXPECT_NEAR((T.linear() * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 0, 1e-12);
  EXPECT_THROW(parseWaypoint("1 2 3"), InvalidArgument);
  EXPECT_THROW(parseWaypoint("1 2 3 0 0 0 1 9"), InvalidArgument);
  EXPECT_THROW(parseWaypoint("1 2 x 0 0 0 1"), InvalidArgument);
  EXPECT_THROW(parseWaypoint("1 2 3e 0 0 0 1"), InvalidArgument);
  EXPECT_THROW(parseWaypoint("1 2 nan 0 0 0 1"), InvalidArgument);
  EXPECT_THROW(parseWaypoint("1 2 3 0 0 0 1.00001"), InvalidArgument);  // |q| off by 1e-5
  EXPECT_NO_THROW(parseWaypoint("1 2 3 0 0 0 1.0000001"));              // within 1e-6

  const std::string dir = fragg::test::testDir();
  const std::string good = dir + "/good.txt", bad = dir + "/bad.txt";
  std::ofstream(good)
      << "# x y z qx qy qz qw\n\n0 0 0 0 0 0 1\n  # indented comment\n1 0 0 0 0 0 1\n";
  std::ofstream(bad) << "0 0 0 0 0 0 1\n0 0 0 0 0 0 2\n";
  EXPECT_EQ(readWaypoints(good).size(), 2u);
  try {
    readWaypoints(bad);
    FAIL() << "a non-unit quaternion was accepted";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.txt:2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(readWaypoints(dir + "/missing.txt"), IoError);
}

}  // namespace
}  // namespace fragg::planning
