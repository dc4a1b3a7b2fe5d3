// MapParams::free_cut_cell: octomap_server's rule for rays cut at max range (the cell at the
// cut point is freed too) against liboctomap's insertPointCloud rule (that cell is left as it
// was), on every traversal (DDA, Bresenham, computeRayKeys's arithmetic); a hit in that cell wins;
// free-only points keep their end cell; the rule travels with a kept scan through a saved map.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "fragg_map/map.h"
#include "test_scenes.h"

namespace fragg {
namespace {

using test::cloudOf;
using test::sensorAtVoxelCentre;

MapParams paramsWith(bool free_cut_cell, RayCast raycast = RayCast::kDda) {
  MapParams p;
  p.backend = Backend::kCpu;
  p.raycast = raycast;
  p.free_cut_cell = free_cut_cell;
  return p;
}

// A point 10 m ahead, max range 2 m: the ray is cut in cell 40 (the sensor sits at the centre
// of cell 0; 0.025 + 2.0 m lies in [2.0, 2.05)).
const SensorModel kRange2 = SensorModel::autoFromCloud(0.0, 2.0);

bool observed(const Map& m, int x) {
  const Cell* c = m.findCell(VoxelKey{x, 0, 0});
  return c != nullptr && c->observed();
}

TEST(FreeCutCellTest, CutCellFreeOnlyUnderTheRuleOnEveryTraversal) {
  for (RayCast raycast : {RayCast::kDda, RayCast::kBresenham, RayCast::kOctomap}) {
    Map liboctomap(paramsWith(false, raycast)), server(paramsWith(true, raycast));
    for (Map* m : {&liboctomap, &server}) {
      const InsertStats s = m->insert(cloudOf({{10.f, 0.f, 0.f}}), sensorAtVoxelCentre(), kRange2);
      EXPECT_EQ(s.rays_free_only, 1u);
      EXPECT_EQ(s.rays_hit, 0u);
      for (int x = 0; x < 40; ++x) EXPECT_EQ(m->state(*m->findCell({x, 0, 0})), CellState::kFree);
      EXPECT_FALSE(observed(*m, 41));
    }
    EXPECT_FALSE(observed(liboctomap, 40)) << toString(raycast);
    ASSERT_TRUE(observed(server, 40)) << toString(raycast);
    const Cell* cut = server.findCell({40, 0, 0});
    EXPECT_EQ(cut->log_odds_fx, server.model().miss_fx);
    EXPECT_EQ(cut->hits, 0);
    EXPECT_EQ(server.knownVoxelCount(), liboctomap.knownVoxelCount() + 1);
  }
}

TEST(FreeCutCellTest, AHitInTheCutCellWins) {
  Map map(paramsWith(true));
  // The second point (1.999 m, inside range) ends in cell 40, where the first ray is cut.
  map.insert(cloudOf({{10.f, 0.f, 0.f}, {1.999f, 0.001f, 0.f}}), sensorAtVoxelCentre(), kRange2);
  const Cell* c = map.findCell({40, 0, 0});
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->log_odds_fx, map.model().hit_fx);
  EXPECT_EQ(map.state(*c), CellState::kOccupied);
}

TEST(FreeCutCellTest, FreeOnlyPointsKeepTheirEndCell) {
  // octomap_server inserts ground points free-only: up to the point (cut at max range), never
  // its own cell, under either rule.
  Map map(paramsWith(true));
  PointCloud cloud = cloudOf({{10.f, 0.f, 0.f}});
  cloud.free_only = {1};
  map.insert(cloud, sensorAtVoxelCentre(), kRange2);
  EXPECT_TRUE(observed(map, 39));
  EXPECT_FALSE(observed(map, 40));
}

TEST(FreeCutCellTest, KeptScanRemembersTheRuleThroughASavedMap) {
  MapParams p = paramsWith(true);
  p.scans.keep = true;
  Map map(p);
  const InsertStats s = map.insert(cloudOf({{10.f, 0.f, 0.f}}), sensorAtVoxelCentre(), kRange2);
  const std::string path = ::testing::TempDir() + "free_cut_cell_test.fgm";
  map.save(path);
  Map loaded = Map::load(path);
  std::remove(path.c_str());
  EXPECT_TRUE(loaded.scanStore().record(s.scan_id).free_cut_cell);
  // The removal walks the scan with its own rule: the cut cell's update is undone as well.
  const Cell before = *loaded.findCell({40, 0, 0});
  EXPECT_EQ(before.log_odds_fx, loaded.model().miss_fx);
  loaded.remove(s.scan_id);
  const Cell* after = loaded.findCell({40, 0, 0});
  const Cell* on_ray = loaded.findCell({20, 0, 0});
  ASSERT_NE(on_ray, nullptr);
  ASSERT_NE(after, nullptr);
  EXPECT_EQ(after->log_odds_fx, on_ray->log_odds_fx);
  EXPECT_EQ(after->observed(), on_ray->observed());
}

}  // namespace
}  // namespace fragg
