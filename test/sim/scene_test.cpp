// Scenes: the simulator's primitives under the BVH (analytic hits on terrain, cylinder caps,
// tessellated spheres), OBJ meshes placed by a scene file, scene files and their errors.
#include "fragg_map/sim/scene.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/sim/primitives.h"
#include "sim_test_util.h"

namespace fragg::sim {
namespace {

using geometry::MeshBvh;
using geometry::RayHit;
using geometry::TriangleMesh;

float hitDistance(const MeshBvh& bvh, Eigen::Vector3f o, Eigen::Vector3f d) {
  RayHit hit;
  if (!bvh.intersect(o, d.normalized(), 1000.f, &hit)) return -1.f;
  return hit.t_m;
}

TEST(SimScene, RayHitsTerrainPlaneCylinderCapAndSphere) {
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

TEST(SimScene, SceneMeshObjectsComeFromObjFilesRelativeToTheScene) {
  const std::string dir = test::testDir();
  TriangleMesh tank;
  tank.appendSolid(makeBox({0, 0, 0}, {1, 1, 2}));
  tank.appendSolid(makeSphere({0.5, 0.5, 2}, 0.5, 4, 8));
  geometry::writeObj(tank, dir + "/tank.obj");
  const Scene s = sceneFromJson(
      R"({"objects": [{"type": "mesh", "obj": "tank.obj", "offset": [10, 20, 0]}]})", dir);
  EXPECT_EQ(s.mesh.solid_count, 2);
  const MeshBvh bvh(s.mesh);
  EXPECT_TRUE(bvh.inside({10.5f, 20.5f, 1.0f}));
  EXPECT_FALSE(bvh.inside({0.5f, 0.5f, 1.0f}));  // moved by the offset
  EXPECT_NEAR(hitDistance(bvh, {10.5f, 20.5f, 10.f}, {0, 0, -1}), 7.5f, 1e-5f);  // sphere top
}

TEST(SimScene, SceneFileObjectsAndErrors) {
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
