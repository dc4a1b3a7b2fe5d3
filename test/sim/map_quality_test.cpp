// Map quality metrics on a hand-made map around a known box (no ray casting involved).
#include "fragg_map/sim/map_quality.h"

#include <gtest/gtest.h>

#include "fragg_map/sim/primitives.h"

namespace fragg::sim {
namespace {

using geometry::MeshBvh;
using geometry::TriangleMesh;

void setCell(Map& map, const VoxelKey& k, int16_t log_odds_fx) {
  map.writeCells([&](CellWriter& cells) {
    Cell c;
    c.log_odds_fx = log_odds_fx;
    cells.set(k, c);
  });
}

// 1 m voxels; the box spans [0.25, 4.75]^3, so voxel keys 0..4 on each axis hold its surface
// (98 surface voxels: the 5^3 shell minus the 3^3 core of keys 1..3) and d = sqrt(3)/2 m.
struct Fixture {
  Map map;
  MeshBvh scene;
  Fixture() : map(params()), scene(boxMesh()) {
    const int16_t occ = map.model().max_fx, free = map.model().min_fx;
    setCell(map, {0, 0, 0}, occ);    // surface voxel, centre 0.25 from the surface: good
    setCell(map, {4, 2, 2}, occ);    // surface voxel, centre 0.25 from the surface: good
    setCell(map, {2, 2, 2}, occ);    // deep inside (1.75 from the surface): wrong
    setCell(map, {-1, 2, 2}, occ);   // outside, 0.75 from the surface (< d): good
    setCell(map, {-3, 2, 2}, occ);   // outside, 2.75 away: wrong
    setCell(map, {2, 2, 1}, free);   // inside, 1.25 deep (> d)
    setCell(map, {2, 2, 0}, free);   // inside, 0.25 deep (a surface voxel)
    setCell(map, {2, 2, -2}, free);  // outside
    setCell(map, {10, 10, 10}, free);
    setCell(map, {1, 1, 1}, 100);  // in the unknown band: neither occupied nor free
  }
  static MapParams params() {
    MapParams p;
    p.resolution_m = 1.0;
    p.backend = Backend::kCpu;
    return p;
  }
  static TriangleMesh boxMesh() {
    TriangleMesh m;
    m.appendSolid(makeBox({0.25, 0.25, 0.25}, {4.75, 4.75, 4.75}));
    return m;
  }
};

TEST(SimMapQuality, HandMadeMapAroundABox) {
  Fixture f;
  const MapQuality q = evaluateMapQuality(f.map, f.scene);
  EXPECT_EQ(q.occupied, 5u);
  EXPECT_EQ(q.occupied_near_surface, 3u);
  EXPECT_DOUBLE_EQ(q.precision(), 0.6);
  EXPECT_EQ(q.free, 4u);
  EXPECT_EQ(q.free_inside, 2u);
  EXPECT_EQ(q.free_inside_deep, 1u);
  EXPECT_DOUBLE_EQ(q.freeError(), 0.5);
  EXPECT_DOUBLE_EQ(q.freeErrorDeep(), 0.25);
  // Observed region (known cells and their 26 neighbours) on the surface:
  //   around (0,0,0): the 7 shell voxels of {0,1}^3; around (4,2,2): the 9 with x = 4 and
  //   y, z in 1..3; around (-1,2,2): the 9 with x = 0 (one, (0,1,1), already counted);
  //   around (2,2,1) and (2,2,0): the 9 with z = 0 and x, y in 1..3 (one, (1,1,0), already
  //   counted): 32. The in-band cell (1,1,1) is observed too: {0..2}^3 holds 19 shell voxels,
  //   6 of them not counted yet, (2,0,0) (0,2,0) (0,0,2) (2,0,1) (1,0,2) (2,0,2): 38.
  // Occupied among them: (0,0,0) and (4,2,2). Known surface voxels: (0,0,0) (4,2,2) (2,2,0)
  // ((1,1,1) is a core voxel, keys 1..3, not a surface voxel).
  EXPECT_EQ(q.surface_observed_occupied, 2u);
  EXPECT_EQ(q.surface_known, 3u);
  EXPECT_DOUBLE_EQ(q.knownSurfaceRecall(), 2.0 / 3.0);
  EXPECT_EQ(q.surface_observed, 38u);
  EXPECT_DOUBLE_EQ(q.recall(), 2.0 / 38.0);
}

}  // namespace
}  // namespace fragg::sim
