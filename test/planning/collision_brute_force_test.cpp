// Random poses of every shape on random maps against a brute force over every cell of a
// generous range with independent overlap tests.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "fragg_map/planning/collision_check.h"
#include "geometry/mesh_test_util.h"
#include "planning/collision_reference.h"

namespace fragg::planning::test {
namespace {

using Reference = std::function<std::vector<VoxelKey>(const Map&, const Eigen::Isometry3d&, bool)>;

// The documented scan order: blocks by z, y, x key, then cells x fastest within a block.
bool scanOrderLess(const VoxelKey& a, const VoxelKey& b) {
  const BlockKey ba = blockKeyOf(a), bb = blockKeyOf(b);
  if (ba.z != bb.z) return ba.z < bb.z;
  if (ba.y != bb.y) return ba.y < bb.y;
  if (ba.x != bb.x) return ba.x < bb.x;
  return cellIndexOf(a) < cellIndexOf(b);
}

void compareRandomPoses(const CollisionShape& shape, const Reference& reference, uint32_t seed,
                        double margin_m = 0.0) {
  const Map map = randomMap(0.1, 16, seed);
  std::mt19937 rng(seed + 1);
  int colliding_poses = 0, free_poses = 0;
  for (const bool unknown : {false, true}) {
    CollisionOptions options;
    options.unknown_is_occupied = unknown;
    options.count_cells = true;
    options.margin_m = margin_m;
    std::vector<Eigen::Isometry3d> poses;
    for (int i = 0; i < 150; ++i) poses.push_back(randomPose(rng, 1.8));
    CollisionOptions first_only = options;
    first_only.count_cells = false;
    const auto batch = checkPoses(map, shape, poses, first_only);
    // A prepared map (every block classified once) answers alike, counts included.
    const PreparedMap prepared(map, unknown);
    const auto prepared_first = checkPoses(prepared, shape, poses, first_only);
    const auto prepared_count = checkPoses(prepared, shape, poses, options);
    for (size_t i = 0; i < poses.size(); ++i) {
      const std::vector<VoxelKey> expected = reference(map, poses[i], unknown);
      const CollisionResult r = checkPose(map, shape, poses[i], options);
      ASSERT_EQ(r.collides, !expected.empty()) << "pose " << i << " unknown " << unknown;
      ASSERT_EQ(r.colliding_cells, expected.size()) << "pose " << i << " unknown " << unknown;
      ASSERT_EQ(batch[i].collides, r.collides) << "pose " << i;
      ASSERT_EQ(prepared_first[i].collides, r.collides) << "pose " << i;
      ASSERT_EQ(prepared_count[i].colliding_cells, r.colliding_cells) << "pose " << i;
      if (r.collides) {
        ASSERT_EQ(prepared_first[i].first_cell, r.first_cell) << "pose " << i;
        ASSERT_EQ(prepared_count[i].first_cell, r.first_cell) << "pose " << i;
      }
      if (r.collides) {
        ++colliding_poses;
        EXPECT_EQ(r.first_cell, *std::min_element(expected.begin(), expected.end(), scanOrderLess))
            << "pose " << i << ": the first colliding cell in scan order";
        EXPECT_EQ(batch[i].first_cell, r.first_cell) << "first cell follows the scan order";
        EXPECT_EQ(batch[i].colliding_cells, 1u);
      } else {
        ++free_poses;
      }
    }
  }
  // Both outcomes must be exercised for the comparison to mean something.
  EXPECT_GT(colliding_poses, 10);
  EXPECT_GT(free_poses, 10);
}

TEST(CollisionBruteForce, OrientedBox) {
  const Vec3 half(0.23, 0.07, 0.11);
  const auto shape = CollisionShape::box(half);
  compareRandomPoses(
      shape,
      [&](const Map& map, const Eigen::Isometry3d& T, bool unknown) {
        return bruteForce(map, T.translation(), half.norm() + 0.3, unknown,
                          [&](const Vec3& c, double h) {
                            return obbObbOverlap(c, Eigen::Matrix3d::Identity(), Vec3::Constant(h),
                                                 T.translation(), T.linear(), half);
                          });
      },
      11);
}

TEST(CollisionBruteForce, Sphere) {
  const double r = 0.17;
  const auto shape = CollisionShape::sphere(r);
  compareRandomPoses(
      shape,
      [&](const Map& map, const Eigen::Isometry3d& T, bool unknown) {
        return bruteForce(map, T.translation(), r + 0.3, unknown, [&](const Vec3& c, double h) {
          return pointBoxDistance(T.translation(), c - Vec3::Constant(h), c + Vec3::Constant(h)) <=
                 r;
        });
      },
      12);
}

TEST(CollisionBruteForce, Capsule) {
  const double r = 0.08, length = 0.45;
  const auto shape = CollisionShape::capsule(r, length);
  compareRandomPoses(
      shape,
      [&](const Map& map, const Eigen::Isometry3d& T, bool unknown) {
        const Vec3 a = T * Vec3(0, 0, -0.5 * length), b = T * Vec3(0, 0, 0.5 * length);
        return bruteForce(
            map, T.translation(), r + length + 0.3, unknown, [&](const Vec3& c, double h) {
              return segmentBoxDistance(a, b, c - Vec3::Constant(h), c + Vec3::Constant(h)) <= r;
            });
      },
      13);
}

TEST(CollisionBruteForce, MarginGrowsSphereAndBox) {
  const double r = 0.12, margin = 0.05;
  compareRandomPoses(
      CollisionShape::sphere(r),
      [&](const Map& map, const Eigen::Isometry3d& T, bool unknown) {
        return bruteForce(map, T.translation(), r + 0.4, unknown, [&](const Vec3& c, double h) {
          return pointBoxDistance(T.translation(), c - Vec3::Constant(h), c + Vec3::Constant(h)) <=
                 r + margin;
        });
      },
      14, margin);
  const Vec3 half(0.2, 0.05, 0.1);
  compareRandomPoses(
      CollisionShape::box(half),
      [&](const Map& map, const Eigen::Isometry3d& T, bool unknown) {
        return bruteForce(
            map, T.translation(), half.norm() + 0.4, unknown, [&](const Vec3& c, double h) {
              return obbObbOverlap(c, Eigen::Matrix3d::Identity(), Vec3::Constant(h),
                                   T.translation(), T.linear(), half + Vec3::Constant(margin));
            });
      },
      15, margin);
}

// A closed convex mesh (an octahedron with one flat face pair cut: a box here, then a
// tetrahedron): a cell collides when a triangle cuts its shrunk cube or its centre is inside.
std::vector<VoxelKey> meshReference(const geometry::TriangleMesh& mesh, const Map& map,
                                    const Eigen::Isometry3d& T, bool unknown, double margin_m) {
  geometry::TriangleMesh moved = mesh;
  double radius = 0;
  for (auto& v : moved.vertices_m) {
    radius = std::max(radius, double(v.norm()));
    v = (T * v.cast<double>()).cast<float>();
  }
  return bruteForce(
      map, T.translation(), radius + margin_m + 0.3, unknown, [&](const Vec3& c, double h) {
        for (const Eigen::Vector3i& t : moved.triangles)
          if (geometry::triangleBoxOverlap(
                  c, Vec3::Constant(h + margin_m), moved.vertices_m[t[0]].cast<double>(),
                  moved.vertices_m[t[1]].cast<double>(), moved.vertices_m[t[2]].cast<double>()))
            return true;
        return insideConvex(moved, c);
      });
}

geometry::TriangleMesh tetrahedron() {
  geometry::TriangleMesh m;
  const Eigen::Vector3f a(0.3f, 0.3f, 0.3f), b(0.3f, -0.3f, -0.3f), c(-0.3f, 0.3f, -0.3f),
      d(-0.3f, -0.3f, 0.3f);
  m.addTriangle(a, c, b, 0);  // inward normals: windings do not matter to the checker
  m.addTriangle(a, b, d, 0);
  m.addTriangle(a, d, c, 0);
  m.addTriangle(b, c, d, 0);
  m.solid_count = 1;
  return m;
}

TEST(CollisionBruteForce, ClosedBoxMesh) {
  const auto mesh = geometry::test::boxSolid({-0.25f, -0.1f, -0.15f}, {0.25f, 0.1f, 0.15f});
  const auto shape = CollisionShape::mesh(mesh);
  ASSERT_TRUE(shape.meshClosed());
  compareRandomPoses(
      shape,
      [&](const Map& map, const Eigen::Isometry3d& T, bool unknown) {
        return meshReference(mesh, map, T, unknown, 0.0);
      },
      16);
}

TEST(CollisionBruteForce, ClosedTetrahedronScaledWithMargin) {
  const auto unit = tetrahedron();
  geometry::TriangleMesh scaled = unit;
  for (auto& v : scaled.vertices_m) v *= 0.8f;
  const auto shape = CollisionShape::mesh(unit, 0.8);
  ASSERT_TRUE(shape.meshClosed());
  // The reference grows each cube by the margin, as the header documents for meshes.
  compareRandomPoses(
      shape,
      [&](const Map& map, const Eigen::Isometry3d& T, bool unknown) {
        return meshReference(scaled, map, T, unknown, 0.03);
      },
      17, 0.03);
}

TEST(CollisionBruteForce, SpheresAgreeWithACoarseTessellation) {
  // Not an exact comparison: every cell a sphere of radius r collides with is within r of it,
  // and the box mesh of the sphere's bounding cube finds a superset.
  const Map map = randomMap(0.1, 16, 18);
  std::mt19937 rng(19);
  const auto sphere = CollisionShape::sphere(0.2);
  const auto cube =
      CollisionShape::mesh(geometry::test::boxSolid({-.2f, -.2f, -.2f}, {.2f, .2f, .2f}));
  CollisionOptions options;
  options.count_cells = true;
  for (int i = 0; i < 100; ++i) {
    Eigen::Isometry3d T = randomPose(rng, 1.5);
    T.linear().setIdentity();
    const auto rs = checkPose(map, sphere, T, options), rc = checkPose(map, cube, T, options);
    EXPECT_LE(rs.colliding_cells, rc.colliding_cells);
    EXPECT_TRUE(!rs.collides || rc.collides);
  }
}

TEST(CollisionBruteForce, BoxMeshFindsTheBoxesCells) {
  // A closed box mesh and the box primitive are the same solid: the same cells, by two
  // different routes (triangles + ray parity, and separating axes).
  const Map map = randomMap(0.1, 16, 20);
  std::mt19937 rng(21);
  const auto box = CollisionShape::box({0.3, 0.2, 0.15});
  const auto mesh =
      CollisionShape::mesh(geometry::test::boxSolid({-0.3f, -0.2f, -0.15f}, {0.3f, 0.2f, 0.15f}));
  for (const bool unknown : {false, true}) {
    CollisionOptions options;
    options.count_cells = true;
    options.unknown_is_occupied = unknown;
    int colliding = 0;
    for (int i = 0; i < 200; ++i) {
      const Eigen::Isometry3d T = randomPose(rng, 1.8);
      const auto rb = checkPose(map, box, T, options), rm = checkPose(map, mesh, T, options);
      EXPECT_EQ(rb.colliding_cells, rm.colliding_cells) << "pose " << i;
      EXPECT_EQ(rb.first_cell, rm.first_cell) << "pose " << i;
      colliding += rb.collides;
    }
    EXPECT_GT(colliding, 10);
  }
}

}  // namespace
}  // namespace fragg::planning::test
