// Scene geometry: analytic ray hits, distances, inside tests, triangle-box overlap, OBJ files.
#include <gtest/gtest.h>

#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/sim/map_quality.h"
#include "fragg_map/sim/mesh_bvh.h"
#include "fragg_map/sim/obj_file.h"
#include "fragg_map/sim/primitives.h"
#include "fragg_map/sim/scene.h"
#include "sim_test_util.h"

namespace fragg::sim {
namespace {

float hitDistance(const MeshBvh& bvh, Eigen::Vector3f o, Eigen::Vector3f d) {
  RayHit hit;
  if (!bvh.intersect(o, d.normalized(), 1000.f, &hit)) return -1.f;
  return hit.t_m;
}

TEST(SimGeometry, RayHitsBoxFacesAtTheAnalyticDistance) {
  TriangleMesh m;
  m.appendSolid(makeBox({-1, -2, -3}, {1, 2, 3}));
  const MeshBvh bvh(m);
  EXPECT_NEAR(hitDistance(bvh, {-5, 0.3f, 0.7f}, {1, 0, 0}), 4.f, 1e-5f);
  EXPECT_NEAR(hitDistance(bvh, {0.2f, 7, -0.4f}, {0, -1, 0}), 5.f, 1e-5f);
  EXPECT_NEAR(hitDistance(bvh, {0.1f, 0.2f, 10}, {0, 0, -1}), 7.f, 1e-5f);
  // Oblique: from (-5, 0, 0) towards +x+z at 45 degrees enters the x = -1 face at z = 4 > 3:
  // it crosses the top face z = 3 instead, at x = -2 (outside): a miss.
  EXPECT_LT(hitDistance(bvh, {-5, 0, 0}, {1, 0, 1}), 0.f);
  EXPECT_NEAR(hitDistance(bvh, {-3, 0, 0}, {1, 0, 1}), 2.f * std::sqrt(2.f), 1e-5f);
  // From inside, the first face ahead.
  EXPECT_NEAR(hitDistance(bvh, {0, 0, 0}, {0, 0, 1}), 3.f, 1e-5f);
}

TEST(SimGeometry, RayHitsTerrainPlaneCylinderCapAndSphere) {
  TriangleMesh m;
  m.append(makeTerrainSlab(-20, -20, 20, 20, 2.0, 1.0,
                           [](double x, double y) { return 0.1 * x - 0.05 * y + 1.0; }));
  m.appendSolid(makeCylinder({30, 0, 0}, {30, 0, 4}, 0.5, 24));
  m.appendSolid(makeSphere({0, 30, 5}, 2.0, 12, 24));
  const MeshBvh bvh(m);
  // Plane z = 0.1 x - 0.05 y + 1 straight down from (3, 4, 10): z = 1.1, t = 8.9.
  EXPECT_NEAR(hitDistance(bvh, {3, 4, 10}, {0, 0, -1}), 8.9f, 1e-4f);
  // Along a slanted ray: (0,0,5) + t * (1, 0, -1)/sqrt2 meets the plane where
  // 5 - s = 0.1 s + 1 (s = t / sqrt2): s = 4 / 1.1.
  EXPECT_NEAR(hitDistance(bvh, {0, 0, 5}, {1, 0, -1}), 4.f / 1.1f * std::sqrt(2.f), 1e-4f);
  // The cylinder's top cap is exact: down onto (30.1, 0.1, 4) from z = 9.
  EXPECT_NEAR(hitDistance(bvh, {30.1f, 0.1f, 9}, {0, 0, -1}), 5.f, 1e-5f);
  // The tessellated sphere lies inside the true sphere, by at most its sag r (1 - cos(pi/12)).
  const float sag = 2.f * (1.f - std::cos(float(M_PI) / 12.f));
  for (const Eigen::Vector3f& d : {Eigen::Vector3f(0, 1, 0), Eigen::Vector3f(0.1f, 1, 0.05f),
                                   Eigen::Vector3f(-0.05f, 1, -0.08f)}) {
    const Eigen::Vector3f o(0, 20, 5), u = d.normalized();
    // Analytic: |o + t u - c| = r.
    const Eigen::Vector3f oc = o - Eigen::Vector3f(0, 30, 5);
    const float b = oc.dot(u), c = oc.squaredNorm() - 4.f;
    const float t_true = -b - std::sqrt(b * b - c);
    const float t = hitDistance(bvh, o, u);
    EXPECT_GE(t, t_true - 1e-4f);
    EXPECT_LE(t, t_true + sag);
  }
}

TEST(SimGeometry, DistanceAndInsidePerSolidEvenWhereSolidsOverlap) {
  TriangleMesh m;
  m.appendSolid(makeBox({0, 0, 0}, {2, 2, 2}));
  m.appendSolid(makeBox({1, 1, 1}, {3, 3, 3}));  // overlaps the first
  const MeshBvh bvh(m);
  EXPECT_TRUE(bvh.inside({0.5f, 0.5f, 0.5f}));
  EXPECT_TRUE(bvh.inside({1.5f, 1.5f, 1.5f}));  // inside both
  EXPECT_TRUE(bvh.inside({2.5f, 2.5f, 2.5f}));
  EXPECT_FALSE(bvh.inside({2.5f, 0.5f, 0.5f}));
  EXPECT_FALSE(bvh.inside({-0.5f, 1.0f, 1.0f}));
  EXPECT_NEAR(bvh.distance({-0.5f, 1.0f, 1.0f}, 10.f), 0.5f, 1e-6f);
  EXPECT_NEAR(bvh.distance({4.f, 4.f, 3.f}, 10.f), std::sqrt(2.f), 1e-6f);
  EXPECT_FLOAT_EQ(bvh.distance({40.f, 0.f, 0.f}, 5.f), 5.f);
  EXPECT_TRUE(bvh.withinDistance({-0.5f, 1.0f, 1.0f}, 0.51f));
  EXPECT_FALSE(bvh.withinDistance({-0.5f, 1.0f, 1.0f}, 0.49f));
}

TEST(SimGeometry, SceneMeshObjectsComeFromObjFilesRelativeToTheScene) {
  const std::string dir = test::testDir();
  TriangleMesh tank;
  tank.appendSolid(makeBox({0, 0, 0}, {1, 1, 2}));
  tank.appendSolid(makeSphere({0.5, 0.5, 2}, 0.5, 4, 8));
  writeObj(tank, dir + "/tank.obj");
  const Scene s = sceneFromJson(
      R"({"objects": [{"type": "mesh", "obj": "tank.obj", "offset": [10, 20, 0]}]})", dir);
  EXPECT_EQ(s.mesh.solid_count, 2);
  const MeshBvh bvh(s.mesh);
  EXPECT_TRUE(bvh.inside({10.5f, 20.5f, 1.0f}));
  EXPECT_FALSE(bvh.inside({0.5f, 0.5f, 1.0f}));  // moved by the offset
  EXPECT_NEAR(hitDistance(bvh, {10.5f, 20.5f, 10.f}, {0, 0, -1}), 7.5f, 1e-5f);  // sphere top
}

TEST(SimGeometry, TriangleBoxOverlap) {
  const Eigen::Vector3d c(0, 0, 0), h(0.5, 0.5, 0.5);
  // A large triangle in the plane z = 0.4 covers the box; z = 0.6 misses it.
  EXPECT_TRUE(triangleBoxOverlap(c, h, {-5, -5, 0.4}, {5, -5, 0.4}, {0, 5, 0.4}));
  EXPECT_FALSE(triangleBoxOverlap(c, h, {-5, -5, 0.6}, {5, -5, 0.6}, {0, 5, 0.6}));
  // A tilted one passing near the corner: x + y + z = 1.6 misses (corner sum 1.5), 1.4 hits.
  auto tilted = [&](double s) { return triangleBoxOverlap(c, h, {s, 0, 0}, {0, s, 0}, {0, 0, s}); };
  EXPECT_TRUE(tilted(1.4));
  EXPECT_FALSE(tilted(1.6));
  // A vertical triangle beside a box edge.
  EXPECT_FALSE(triangleBoxOverlap(c, h, {0.9, -0.9, -2}, {0.9, -0.9, 2}, {2, 0.2, 0}));
}

TEST(SimGeometry, ObjRoundTripKeepsVerticesTrianglesAndSolids) {
  TriangleMesh m;
  m.appendSolid(makeBox({-1.25, 0.1, 0}, {3.3, 2.7, 1.9}));
  m.appendSolid(makeSphere({1, 2, 3}, 0.77, 6, 9));
  m.appendSolid(makeCylinder({0, 0, 0}, {1, 2, 3}, 0.31, 7));
  const std::string path = test::testDir() + "/m.obj";
  writeObj(m, path);
  const TriangleMesh r = readObj(path);
  ASSERT_EQ(r.solid_count, 3);
  ASSERT_EQ(r.triangles.size(), m.triangles.size());
  // Faces are written grouped by solid; here solids are already contiguous, so order is kept.
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    EXPECT_EQ(r.solid_of_triangle[i], m.solid_of_triangle[i]);
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(r.vertices_m[r.triangles[i][k]], m.vertices_m[m.triangles[i][k]]);  // bit-exact
  }
}

TEST(SimGeometry, ObjReaderRejectsBadFaces) {
  const std::string dir = test::testDir();
  {
    std::ofstream f(dir + "/bad.obj");
    f << "v 0 0 0\nv 1 0 0\nf 1 2 3\n";
  }
  EXPECT_THROW(readObj(dir + "/bad.obj"), IoError);
  {
    std::ofstream f(dir + "/quad.obj");
    f << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng a\nf 1/1 2/2/2 3//3 -1\n";
  }
  const TriangleMesh q = readObj(dir + "/quad.obj");
  EXPECT_EQ(q.triangles.size(), 2u);  // the quad is fanned
  EXPECT_EQ(q.solid_count, 1);
  EXPECT_THROW(readObj(dir + "/missing.obj"), IoError);
}

TEST(SimGeometry, SceneFileObjectsAndErrors) {
  const Scene s = sceneFromJson(R"({"name": "t",
    "ground": {"extent": [-10, -10, 10, 10], "slope": [0.1, 0], "cell": 2, "thickness": 1},
    "objects": [{"type": "building", "footprint": [0, 0, 2, 2], "height": 3},
                {"type": "tree", "at": [5, 5]},
                {"type": "pipe", "from": [0, 0, 1], "to": [3, 0, 1], "radius": 0.2}],
    "trajectories": {"a": {"waypoints": [[0, 0], [5, 0, 1]], "speed": 2, "rate": 4}}})");
  EXPECT_EQ(s.mesh.solid_count, 1 + 1 + 2 + 1);  // ground, building, trunk + crown, pipe
  EXPECT_NEAR(s.terrain.heightAt(3, 0), 0.3, 1e-12);
  ASSERT_EQ(s.trajectories.count("a"), 1u);
  EXPECT_EQ(s.trajectories.at("a").waypoints_m.size(), 2u);
  // The building's roof is at ground height at its centre (0.1) + 3.
  const MeshBvh bvh(s.mesh);
  RayHit hit;
  ASSERT_TRUE(bvh.intersect({1.0f, 1.0f, 10.f}, {0, 0, -1}, 100.f, &hit));
  EXPECT_NEAR(hit.t_m, 10.f - 3.1f, 1e-5f);
  EXPECT_THROW(sceneFromJson(R"({"objects": [{"type": "cone"}]})"), InvalidArgument);
  EXPECT_THROW(sceneFromJson(R"({"objects": [{"type": "mesh", "obj": "missing.obj"}]})"), IoError);
  EXPECT_THROW(sceneFromJson(R"({"objects": [{"type": "box", "min": [0, 0]}]})"), InvalidArgument);
  EXPECT_THROW(sceneFromJson("{not json"), IoError);
}

}  // namespace
}  // namespace fragg::sim
