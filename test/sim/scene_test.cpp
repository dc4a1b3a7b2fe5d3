// Scenes: the simulator's primitives under the BVH (analytic hits on terrain, cylinder caps,
// tessellated spheres), OBJ meshes placed by a scene file, scene files and their errors.
#include "fragg_map/sim/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

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

// A tile scene file (ground, a building, a box mesh from an OBJ file, a trajectory) for the
// "tile" section.
std::string writeTileScene(const std::string& dir) {
  TriangleMesh crate;
  crate.appendSolid(makeBox({0, 0, 0}, {1, 1, 1}));
  geometry::writeObj(crate, dir + "/crate.obj");
  const std::string path = dir + "/tile.json";
  std::ofstream(path) << R"({"name": "tile",
    "ground": {"extent": [-10, -10, 10, 10], "slope": [0.1, 0.05], "cell": 2, "thickness": 1},
    "objects": [{"type": "building", "footprint": [0, 0, 2, 2], "height": 3},
                {"type": "mesh", "obj": "crate.obj", "offset": [-5, -5, 20]}],
    "trajectories": {"t": {"waypoints": [[0, 0], [5, 0]]}}})";
  return path;
}

TEST(SimScene, TileRepeatsAnotherScenesObjectsOnAGrownGround) {
  const std::string dir = test::testDir();
  writeTileScene(dir);
  const std::string sub = dir + "/sub";
  ASSERT_EQ(std::system(("mkdir -p '" + sub + "'").c_str()), 0);
  // The tiling scene lives in another folder: the tile's OBJ path stays relative to the tile.
  const Scene s = sceneFromJson(R"({"name": "big",
    "tile": {"scene": "../tile.json", "count": [3, 2], "step": [20, 30]},
    "objects": [{"type": "box", "min": [100, 100, 0], "max": [101, 101, 1]}],
    "trajectories": {"own": {"waypoints": [[0, 0], [1, 0]]}}})",
                                sub);
  EXPECT_EQ(s.name, "big");
  EXPECT_EQ(s.mesh.solid_count, 1 + 3 * 2 * 2 + 1);  // ground, 6 x (building, crate), own box
  EXPECT_EQ(s.terrain.x0_m, -10);
  EXPECT_EQ(s.terrain.y0_m, -10);
  EXPECT_EQ(s.terrain.x1_m, 10 + 2 * 20);
  EXPECT_EQ(s.terrain.y1_m, 10 + 1 * 30);
  EXPECT_NEAR(s.terrain.heightAt(40, 30), 0.1 * 40 + 0.05 * 30, 1e-12);
  ASSERT_EQ(s.trajectories.size(), 1u);  // the tile's own trajectories are not taken
  EXPECT_EQ(s.trajectories.count("own"), 1u);
  const MeshBvh bvh(s.mesh);
  for (int ix = 0; ix < 3; ++ix)
    for (int iy = 0; iy < 2; ++iy) {
      SCOPED_TRACE(testing::Message() << "tile " << ix << " " << iy);
      const float x = 1.0f + 20 * ix, y = 1.0f + 30 * iy;
      // Each building stands on the ground where its tile puts it: roof = ground there + 3.
      EXPECT_NEAR(hitDistance(bvh, {x, y, 50.f}, {0, 0, -1}), 50.f - (s.terrain.heightAt(x, y) + 3),
                  1e-4f);
      EXPECT_TRUE(bvh.inside({-4.5f + 20 * ix, -4.5f + 30 * iy, 20.5f}));  // the crate
    }
  EXPECT_FALSE(bvh.inside({-4.5f + 60, -4.5f, 20.5f}));  // no fourth tile along x
  EXPECT_FALSE(bvh.inside({-4.5f, -4.5f + 60, 20.5f}));  // no third along y
  EXPECT_TRUE(bvh.inside({100.5f, 100.5f, 0.5f}));       // the scene's own objects come too

  // The scene's own ground replaces the tile's.
  const Scene own = sceneFromJson(R"({"tile": {"scene": "tile.json", "count": [2, 1],
    "step": [20, 0]}, "ground": {"extent": [-1, -1, 1, 1]}})",
                                  dir);
  EXPECT_EQ(own.terrain.x1_m, 1);
  EXPECT_EQ(own.terrain.slope_x, 0);
}

TEST(SimScene, TileErrors) {
  const std::string dir = test::testDir();
  writeTileScene(dir);
  auto tiled = [&](const std::string& tile) {
    return sceneFromJson(R"({"tile": )" + tile + "}", dir);
  };
  EXPECT_NO_THROW(tiled(R"({"scene": "tile.json", "count": [1, 1], "step": [0, 0]})"));
  for (const char* bad : {R"({"scene": "tile.json", "count": [0, 1], "step": [1, 1]})",
                          R"({"scene": "tile.json", "count": [1.5, 1], "step": [1, 1]})",
                          R"({"scene": "tile.json", "count": [1000, 1000], "step": [1, 1]})",
                          R"({"scene": "tile.json", "count": [1, 1]})",
                          R"({"scene": "tile.json", "count": [1], "step": [1, 1]})",
                          R"({"count": [1, 1], "step": [1, 1]})", R"("tile.json")"}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(tiled(bad), InvalidArgument);
  }
  EXPECT_THROW(tiled(R"({"scene": "missing.json", "count": [1, 1], "step": [1, 1]})"), IoError);
  std::ofstream(dir + "/nested.json") << R"({"tile": {"scene": "tile.json", "count": [1, 1],
    "step": [1, 1]}})";
  EXPECT_THROW(tiled(R"({"scene": "nested.json", "count": [1, 1], "step": [1, 1]})"),
               InvalidArgument);
  std::ofstream(dir + "/broken.json") << "{not json";
  EXPECT_THROW(tiled(R"({"scene": "broken.json", "count": [1, 1], "step": [1, 1]})"), IoError);
}

}  // namespace
}  // namespace fragg::sim
