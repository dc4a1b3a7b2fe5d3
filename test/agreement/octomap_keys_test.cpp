// RayCast::kOctomap against liboctomap itself: traverseOctomapKeys names the cells
// OcTreeBaseImpl::computeRayKeys names, in the same order, on long random rays (where the exact
// DDA's float arithmetic parts from OctoMap's), and a map built with it agrees with OctoMap's
// insertPointCloud on the real VLS-128 scan at 5 cm and 30 m (the exact DDA: 99.9582 %).
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "fragg_map/io/point_file.h"
#include "fragg_map/raycast_octomap.h"
#include "octomap_reference.h"

namespace fragg {
namespace {

constexpr int kTreeMaxVal = 32768;  // OctoMap's key offset at its default depth

struct Collect {
  std::vector<VoxelKey> cells;
  std::vector<bool> hits;
  std::vector<int> entries;
  void operator()(const VoxelKey& k, bool hit, int entry) {
    cells.push_back(k);
    hits.push_back(hit);
    entries.push_back(entry);
  }
};

/// computeRayKeys's key ray, in fragg keys.
std::vector<VoxelKey> octomapRay(const octomap::OcTree& tree, const octomap::point3d& o,
                                 const octomap::point3d& e) {
  octomap::KeyRay ray;
  EXPECT_TRUE(tree.computeRayKeys(o, e, ray));
  std::vector<VoxelKey> out;
  for (const octomap::OcTreeKey& k : ray)
    out.push_back(
        VoxelKey{int(k[0]) - kTreeMaxVal, int(k[1]) - kTreeMaxVal, int(k[2]) - kTreeMaxVal});
  return out;
}

RayMetres rayOf(const octomap::point3d& o, const octomap::point3d& e, double res, bool hit) {
  return RayMetres{{o.x(), o.y(), o.z()}, {e.x(), e.y(), e.z()}, res, 1.0 / res, hit};
}

/// Random rays up to 120 m from origins up to 200 m from the map's origin, several
/// resolutions: the free cells are computeRayKeys's, in order; a hit adds the end point's
/// cell (coordToKey); the entry codes say which block each cell is in.
TEST(OctomapKeysTest, SameCellsAsComputeRayKeysOnLongRandomRays) {
  std::mt19937 rng(38);
  std::uniform_real_distribution<float> pos(-200.f, 200.f), unit(-1.f, 1.f), len(0.f, 120.f);
  size_t rays = 0, cells = 0;
  for (double res : {0.05, 0.1, 0.2, 0.03}) {
    const octomap::OcTree tree(res);
    for (int i = 0; i < 1000; ++i) {
      const octomap::point3d o(pos(rng), pos(rng), pos(rng) * 0.1f);
      octomap::point3d d(unit(rng), unit(rng), unit(rng));
      if (i % 10 == 0) d.z() = 0.f;  // planar rays: a zero direction component
      if (d.norm() < 1e-3) continue;
      const octomap::point3d e = o + d.normalized() * len(rng);
      const std::vector<VoxelKey> expected = octomapRay(tree, o, e);
      Collect got;
      const int visited = traverseOctomapKeys(rayOf(o, e, res, true), got);
      ASSERT_EQ(static_cast<size_t>(visited), expected.size() + 1) << "res " << res << " ray " << i;
      for (size_t k = 0; k < expected.size(); ++k) {
        ASSERT_EQ(got.cells[k], expected[k]) << "res " << res << " ray " << i << " cell " << k;
        ASSERT_FALSE(got.hits[k]);
      }
      const octomap::OcTreeKey end = tree.coordToKey(e);
      EXPECT_EQ(got.cells.back(), (VoxelKey{int(end[0]) - kTreeMaxVal, int(end[1]) - kTreeMaxVal,
                                            int(end[2]) - kTreeMaxVal}));
      EXPECT_TRUE(got.hits.back());
      EXPECT_EQ(got.entries[0], kUnknownBlock);
      for (size_t k = 1; k < got.cells.size(); ++k)
        EXPECT_EQ(got.entries[k], entryAfter(got.cells[k - 1], got.cells[k]));
      ++rays;
      cells += expected.size();
    }
  }
  std::printf("[octomap_keys] %zu rays, %zu cells: the same as computeRayKeys\n", rays, cells);
}

/// A free-only ray visits computeRayKeys's cells only; with end_is_free its end cell as free.
TEST(OctomapKeysTest, FreeOnlyRaysAndTheFreeCutCell) {
  const double res = 0.05;
  const octomap::OcTree tree(res);
  const octomap::point3d o(1.01f, -2.37f, 0.4f), e(-25.3f, 17.9f, -3.1f);
  const std::vector<VoxelKey> expected = octomapRay(tree, o, e);
  Collect free_only;
  RayMetres ray = rayOf(o, e, res, false);
  EXPECT_EQ(static_cast<size_t>(traverseOctomapKeys(ray, free_only)), expected.size());
  EXPECT_EQ(free_only.cells, expected);
  ray.end_is_free = true;
  Collect cut;
  EXPECT_EQ(static_cast<size_t>(traverseOctomapKeys(ray, cut)), expected.size() + 1);
  EXPECT_FALSE(cut.hits.back());
  const octomap::OcTreeKey end = tree.coordToKey(e);
  EXPECT_EQ(cut.cells.back(), (VoxelKey{int(end[0]) - kTreeMaxVal, int(end[1]) - kTreeMaxVal,
                                        int(end[2]) - kTreeMaxVal}));
}

/// A hit's clearing margin leaves out the free cells whose exit lies inside it, and only those.
TEST(OctomapKeysTest, ClearingMarginLeavesOutTheLastFreeCells) {
  const double res = 0.1;
  const octomap::point3d o(0.05f, 0.05f, 0.05f), e(10.05f, 0.05f, 0.05f);  // along x, 100 cells
  RayMetres ray = rayOf(o, e, res, true);
  Collect plain, kept;
  traverseOctomapKeys(ray, plain);
  ray.keep_v = 3.2f;  // 0.32 m: cells whose exit lies beyond 9.68 m are left out
  traverseOctomapKeys(ray, kept);
  ASSERT_EQ(plain.cells.size(), 101u);
  ASSERT_EQ(kept.cells.size(), plain.cells.size() - 3);  // cells 97..99: exits 9.75 .. 9.95 m
  EXPECT_EQ(kept.cells.back(), plain.cells.back());
  EXPECT_TRUE(kept.hits.back());
  EXPECT_EQ(kept.cells[kept.cells.size() - 2].x, 96);
}

/// The real VLS-128 scan (208,680 points, outdoor, up to 239 m; every 256th point) at 5 cm and
/// 30 m, one insertion each: with RayCast::kOctomap the map names OctoMap's cells.
TEST(OctomapKeysTest, Vls128ScanAgreesWithOctomap) {
  const PointCloud whole = readPointFile(std::string(FRAGG_REAL_DATA) +
                                         "/nebula_single_scans/vls128_1585897255376374245.pcd");
  Scan scan;  // every 256th point: OctoMap takes seconds for the whole scan, compare as long
  for (size_t i = 0; i < whole.size(); i += 256) scan.cloud.points_S.push_back(whole.points_S[i]);
  scan.T_map_sensor = Eigen::Isometry3d::Identity();
  const double res = 0.05, max_range_m = 30.0;
  MapParams params;
  params.backend = Backend::kCpu;
  params.resolution_m = res;
  params.occupancy.unknown_band = 0.0;  // OctoMap's threshold: occupied iff p > 0.5
  octomap::OcTree tree = test::octomapWithParamsOf(params);
  test::insertIntoOctomap(tree, scan, max_range_m);
  for (RayCast raycast : {RayCast::kOctomap, RayCast::kDda}) {
    params.raycast = raycast;
    Map map(params);
    map.insert(scan.cloud, scan.T_map_sensor, SensorModel::autoFromCloud(0.0, max_range_m));
    const test::Agreement a = test::compareWithOctomap(map, tree);
    std::printf(
        "[octomap_keys] VLS-128, 5 cm, 30 m, raycast %s: either-known %.4f %% (only fragg %llu, "
        "only OctoMap %llu, both %llu, same state %llu)\n",
        toString(raycast), 100 * a.eitherRatio(), static_cast<unsigned long long>(a.only_fragg),
        static_cast<unsigned long long>(a.only_octomap), static_cast<unsigned long long>(a.both),
        static_cast<unsigned long long>(a.both_same));
    if (raycast == RayCast::kOctomap) {
      EXPECT_GT(a.both, 100000u);
      EXPECT_GE(a.eitherRatio(), 0.99999);
    }
  }
}

}  // namespace
}  // namespace fragg
