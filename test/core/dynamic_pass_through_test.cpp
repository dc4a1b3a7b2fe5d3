// Dynamic-aware mapping (MapParams::dynamic) under the pass-through rule (VoidSpaceRule::
// kPassThrough, the default): bad option values refused; the first scan, and any
// scan with nothing void, integrates as OctoMap's rule does; over a sequence with a person
// walking through confidently free space, every scan equals a brute-force reference (each
// point classified from the reference map's cells, then inserted with the dynamic points
// marked free-only into a map with the option off, then the occupied cells with an observed
// neighbourhood that took a miss made void), masks included; the dynamic points are handed
// back.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "dynamic_scene.h"
#include "fragg_map/cell_writer.h"
#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/occupancy.h"
#include "same_map.h"
#include "state_masks_check.h"

namespace fragg {
namespace {

using test::kDynamicScenePersonY;

// The shared scene (dynamic_scene.h) under the pass-through rule.
MapParams dynamicParams(bool enabled, int known_radius_cells = 1) {
  return test::dynamicSceneParams(enabled, VoidSpaceRule::kPassThrough, known_radius_cells);
}
PointCloud sceneCloud(int person_y) { return test::dynamicSceneCloud(person_y); }
Eigen::Isometry3d sensorPose() { return test::dynamicScenePose(); }
Eigen::Vector3f cellCentre(int x, int y, int z) { return test::dynamicSceneCell(x, y, z); }

// Brute force: point i is dynamic when its cell is void and every cell within the radius has
// been observed, in `ref` as it is now.
bool observedAround(const Map& ref, const VoxelKey& k, int r) {
  for (int dz = -r; dz <= r; ++dz)
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const Cell* n = ref.findCell({k.x + dx, k.y + dy, k.z + dz});
        if (!n || !n->observed()) return false;
      }
  return true;
}

std::vector<uint8_t> referenceDynamic(const Map& ref, const PointCloud& cloud,
                                      const DynamicParams& d) {
  const int16_t void_fx = logOddsFxOf(d.void_probability);
  std::vector<uint8_t> dynamic(cloud.size(), 0);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const VoxelKey k = ref.keyOf(sensorPose() * cloud.points_S[i].cast<double>());
    const Cell* c = ref.findCell(k);
    if (!c || !c->observed() || c->log_odds_fx > void_fx) continue;
    dynamic[i] = observedAround(ref, k, d.known_radius_cells) ? 1 : 0;
  }
  return dynamic;
}

TEST(PassThroughRuleTest, BadOptionValuesAreRefused) {
  auto refused = [](auto edit) {
    MapParams p = dynamicParams(true);
    edit(p);
    EXPECT_THROW(Map{p}, InvalidArgument);
  };
  refused([](MapParams& p) { p.dynamic.void_probability = 0.0; });
  refused([](MapParams& p) { p.dynamic.void_probability = 0.46; });  // inside the unknown band
  refused([](MapParams& p) { p.dynamic.void_probability = std::nan(""); });
  refused([](MapParams& p) { p.dynamic.void_probability = 0.1; });  // below clamp_min 0.12
  refused([](MapParams& p) { p.dynamic.known_radius_cells = -1; });
  refused([](MapParams& p) { p.dynamic.known_radius_cells = 3; });
  refused([](MapParams& p) { p.scans.keep = true; });
  refused([](MapParams& p) { p.backend = Backend::kCuda; });
  // Off, the values are not looked at (the default path is OctoMap's).
  MapParams off = dynamicParams(false);
  off.dynamic.void_probability = 0.0;
  EXPECT_NO_THROW(Map{off});
}

TEST(PassThroughRuleTest, NothingVoidIntegratesAsWithTheOptionOff) {
  Map on(dynamicParams(true)), off(dynamicParams(false));
  const PointCloud cloud = sceneCloud(0);
  const InsertStats s_on = on.insert(cloud, sensorPose(), SensorModel::autoFromCloud());
  const InsertStats s_off = off.insert(cloud, sensorPose(), SensorModel::autoFromCloud());
  EXPECT_EQ(s_on.rays_dynamic, 0u);
  EXPECT_EQ(s_on.rays_hit, s_off.rays_hit);
  EXPECT_TRUE(on.lastDynamicPoints_S().empty());
  test::expectSameMap(on, off, "first scan");
}

// The sequence through a map with the option on and through the brute-force reference, both
// with the neighbourhood radius `r`; checks every scan, returns the counts.
struct PersonRun {
  uint64_t dynamic_total = 0, void_but_static = 0, resets = 0;
};

void walkPerson(int r, Map* out_map, PersonRun* run) {
  const MapParams params = dynamicParams(true, r);
  Map& map = *out_map;
  Map ref(dynamicParams(false));
  uint64_t& dynamic_total = run->dynamic_total;
  uint64_t& void_but_static = run->void_but_static;
  uint64_t& resets = run->resets;
  for (size_t step = 0; step < std::size(kDynamicScenePersonY); ++step) {
    const PointCloud cloud = sceneCloud(kDynamicScenePersonY[step]);
    const std::vector<uint8_t> expected = referenceDynamic(ref, cloud, params.dynamic);
    // Points in void cells that the neighbourhood keeps static (the edge point).
    for (size_t i = 0; i < cloud.size(); ++i) {
      const Cell* c = ref.findCell(ref.keyOf(sensorPose() * cloud.points_S[i].cast<double>()));
      if (!expected[i] && c && c->observed() &&
          c->log_odds_fx <= logOddsFxOf(params.dynamic.void_probability))
        ++void_but_static;
    }
    // Pass-through candidates: the reference's occupied cells whose neighbourhood has been
    // observed, before the scan.
    std::vector<std::pair<VoxelKey, Cell>> occupied_before;
    ref.forEachBlock([&](const BlockKey& bk, const Block& block) {
      for (int ci = 0; ci < kCellsPerBlock; ++ci)
        if (ref.state(block.cells[ci]) == CellState::kOccupied &&
            observedAround(ref, voxelKeyOf(bk, ci), params.dynamic.known_radius_cells))
          occupied_before.emplace_back(voxelKeyOf(bk, ci), block.cells[ci]);
    });
    PointCloud marked = cloud;
    marked.free_only.assign(expected.begin(), expected.end());
    ref.insert(marked, sensorPose(), SensorModel::autoFromCloud());
    // Those that took a miss (a ray passed through, none ended there) become void.
    const OccupancyModel model = OccupancyModel::fromParams(params.occupancy);
    ref.writeCells([&](CellWriter& w) {
      for (const auto& [key, before] : occupied_before) {
        const Cell* now = ref.findCell(key);
        if (now->hits == before.hits &&
            now->log_odds_fx == model.updated(before.log_odds_fx, false)) {
          w.set(key, Cell{before.hits, logOddsFxOf(params.dynamic.void_probability)});
          ++resets;
        }
      }
    });
    const InsertStats s = map.insert(cloud, sensorPose(), SensorModel::autoFromCloud());

    std::vector<Eigen::Vector3f> expected_points;
    for (size_t i = 0; i < cloud.size(); ++i)
      if (expected[i]) expected_points.push_back(cloud.points_S[i]);
    EXPECT_EQ(s.rays_dynamic, expected_points.size()) << "scan " << step;
    EXPECT_EQ(s.rays_hit + s.rays_dynamic, cloud.size()) << "scan " << step;  // all hits
    EXPECT_EQ(map.lastDynamicPoints_S(), expected_points) << "scan " << step;
    test::expectSameMap(map, ref, "scan");
    EXPECT_EQ(test::blocksWithStaleMasks(map), 0u) << "scan " << step;
    dynamic_total += s.rays_dynamic;
  }
}

TEST(PassThroughRuleTest, PersonWalkingThroughVoidSpaceMatchesBruteForce) {
  Map wide(dynamicParams(true, 2));
  PersonRun wide_run;
  walkPerson(2, &wide, &wide_run);  // the default radius: fewer cells qualify
  EXPECT_GT(wide_run.dynamic_total, 0u);
  Map map(dynamicParams(true, 1));
  PersonRun run;
  walkPerson(1, &map, &run);
  const uint64_t dynamic_total = run.dynamic_total, void_but_static = run.void_but_static,
                 resets = run.resets;
  EXPECT_GT(dynamic_total, wide_run.dynamic_total);
  EXPECT_GT(dynamic_total, 50u);  // the person's columns, after the room became void
  EXPECT_GT(void_but_static, 0u);
  EXPECT_GE(resets, 10u);  // the first standing place, cleared by the rays through it
  // No ghost: no cell of the person's path that the empty room's rays had cleared (y within
  // +-7.5 and z within -9..5 at x = 20, a cell's neighbours included) is occupied at the end.
  for (int y = -4; y <= 4; y += 4)
    for (int z = -8; z <= 4; ++z) {
      const Cell* c = map.findCell(map.keyOf(sensorPose() * cellCentre(20, y, z).cast<double>()));
      ASSERT_NE(c, nullptr);
      EXPECT_NE(map.state(*c), CellState::kOccupied) << y << " " << z;
    }
}

TEST(PassThroughRuleTest, WithoutTheOptionThePersonLeavesATrail) {
  Map map(dynamicParams(false));
  for (int y : kDynamicScenePersonY)
    map.insert(sceneCloud(y), sensorPose(), SensorModel::autoFromCloud());
  int occupied = 0;
  for (int y = -4; y <= 4; y += 4)
    for (int z = -8; z <= 4; ++z) {
      const Cell* c = map.findCell(map.keyOf(sensorPose() * cellCentre(20, y, z).cast<double>()));
      occupied += c && map.state(*c) == CellState::kOccupied ? 1 : 0;
    }
  EXPECT_GE(occupied, 13);  // where the person stood: what the option leaves out
}

}  // namespace
}  // namespace fragg
