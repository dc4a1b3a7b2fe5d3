// projected_map on octomap_server's grid: octomapServerGridSpan against octomap_server's own
// arithmetic run on liboctomap (handlePreNodeTraversal of octomap_mapping kinetic-devel
// efa61ca: getMetricMin/Max, coordToKeyChecked at depth 16, zero padding), and the server's
// incremental cache against projectedMap with the option.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <random>
#include <utility>
#include <vector>

#include "fragg_map/map.h"
#include "fragg_map/ros/output_cache.h"
#include "fragg_map/ros/projected_map.h"

namespace {

using fragg::ros::GridSpan;
using fragg::ros::octomapServerGridSpan;

// What octomap_server computes for a tree holding cells at x keys lo and hi (y, z at 0):
// the x span of its grid, as fragg voxel keys.
GridSpan octomapServerSpan(int lo, int hi, double res) {
  octomap::OcTree tree(res);
  for (int x : {lo, hi}) tree.updateNode(octomap::OcTreeKey(x + 32768, 32768, 32768), true);
  double min_x, min_y, min_z, max_x, max_y, max_z;
  tree.getMetricMin(min_x, min_y, min_z);
  tree.getMetricMax(max_x, max_y, max_z);
  min_x = std::min(min_x, -0.5 * 0.0);  // m_minSizeX = 0
  max_x = std::max(max_x, 0.5 * 0.0);
  octomap::OcTreeKey padded_min, padded_max;
  EXPECT_TRUE(tree.coordToKeyChecked(octomap::point3d(min_x, min_y, min_z), 16, padded_min));
  EXPECT_TRUE(tree.coordToKeyChecked(octomap::point3d(max_x, max_y, max_z), 16, padded_max));
  return {int64_t{padded_min[0]} - 32768, int64_t{padded_max[0]} - 32768};
}

TEST(OctomapGridBounds, TheIssuesCaseAndTheOrigin) {
  // Issue 38's projected_map: 276 cells from -12.60 (fragg) against 278 from -12.65.
  GridSpan s = octomapServerGridSpan(-252, 23, 0.05);
  EXPECT_EQ(s.lo, -253);
  EXPECT_EQ(s.hi - s.lo + 1, 278);
  // Cells away from the origin: the grid still takes in the origin's cell (here the upper
  // face at 2.05 m, as a float, keys to 40 itself: 41 cells from 0.00, as measured with
  // liboctomap for docs/ros.md).
  s = octomapServerGridSpan(3, 40, 0.05);
  EXPECT_EQ(s.lo, 0);
  EXPECT_EQ(s.hi, 40);
  s = octomapServerGridSpan(-40, -3, 0.05);
  EXPECT_EQ(s.lo, -40);
  EXPECT_EQ(s.hi, 0);
  // -100..100: the upper face keys one beyond (202 cells, as measured).
  s = octomapServerGridSpan(-100, 100, 0.05);
  EXPECT_EQ(s.hi - s.lo + 1, 202);
}

TEST(OctomapGridBounds, SameAsLiboctomapWithOctomapServersArithmetic) {
  std::mt19937 rng(38);
  std::uniform_int_distribution<int> key(-3000, 3000);
  int checked = 0;
  for (double res : {0.05, 0.1, 0.02, 0.25, 0.03}) {
    for (int i = 0; i < 300; ++i) {
      int lo = key(rng), hi = key(rng);
      if (lo > hi) std::swap(lo, hi);
      const GridSpan want = octomapServerSpan(lo, hi, res);
      const GridSpan got = octomapServerGridSpan(lo, hi, res);
      ASSERT_EQ(got.lo, want.lo) << "res " << res << " keys " << lo << " " << hi;
      ASSERT_EQ(got.hi, want.hi) << "res " << res << " keys " << lo << " " << hi;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 1500);
}

TEST(OctomapGridBounds, CacheAndProjectedMapAgreeWithTheOption) {
  fragg::MapParams p;
  p.resolution_m = 0.05;
  p.backend = fragg::Backend::kCpu;
  p.threads = 1;
  fragg::Map map(p);
  map.writeCells([&](fragg::CellWriter& w) {
    fragg::Cell c;
    c.log_odds_fx = map.model().max_fx;
    w.set({-252, 7, 3}, c);
    w.set({23, 40, 3}, c);
    c.log_odds_fx = map.model().min_fx;
    w.set({5, 12, 3}, c);
  });
  fragg::ros::OutputCacheOptions options;
  options.octomap_bounds = true;
  fragg::ros::MapOutputCache cache(options);
  cache.update(map);
  const nav_msgs::OccupancyGrid got = cache.projectedMap("map", ::ros::Time(0));
  const nav_msgs::OccupancyGrid want =
      fragg::ros::projectedMap(map, -1e9, 1e9, "map", ::ros::Time(0), false, true);
  EXPECT_EQ(want.info.width, 278u);
  const GridSpan y = octomapServerSpan(7, 40, 0.05);  // y keys 0 (the origin) .. one beyond 40
  EXPECT_EQ(y.lo, 0);
  EXPECT_EQ(want.info.height, static_cast<uint32_t>(y.hi - y.lo + 1));
  EXPECT_NEAR(want.info.origin.position.x, -253 * 0.05, 1e-9);
  EXPECT_NEAR(want.info.origin.position.y, 0.0, 1e-9);
  EXPECT_EQ(got.info.width, want.info.width);
  EXPECT_EQ(got.info.height, want.info.height);
  EXPECT_NEAR(got.info.origin.position.x, want.info.origin.position.x, 1e-9);
  EXPECT_NEAR(got.info.origin.position.y, want.info.origin.position.y, 1e-9);
  EXPECT_EQ(got.data, want.data);
  // The cells themselves where the map has them; the added columns unknown.
  auto at = [&](int x, int y) { return want.data[(y - 0) * want.info.width + (x + 253)]; };
  EXPECT_EQ(at(-252, 7), fragg::ros::grid_value::kOccupied);
  EXPECT_EQ(at(5, 12), fragg::ros::grid_value::kFree);
  EXPECT_EQ(at(-253, 7), fragg::ros::grid_value::kUnknown);
  EXPECT_EQ(at(24, 40), fragg::ros::grid_value::kUnknown);
}

}  // namespace
