// Dynamic-aware mapping (MapParams::dynamic) under DUFOMap's surround rule
// (VoidSpaceRule::kSurround; the pass-through rule has dynamic_pass_through_test.cpp): bad
// option values refused, the rule's among them; the first scan, and any
// scan with nothing void, integrates as OctoMap's rule does; over a sequence with a person
// walking through space the sensor sees all around, every scan equals a brute-force reference
// (each point dynamic when its cell is void in the reference map; the scan inserted with those
// points free-only into a map with the option off; then each cell the scan passed through
// (taken from the same scan inserted into an empty map) set by the surround test: void when
// every neighbour is passed through by the scan or known (occupied or free) before it (occupied
// ones left by earlier hits included), and hit by none of its rays, else one unit above the clamp
// unless void already), masks included; no floor or wall point is ever dynamic; the dynamic points
// are handed back.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "dynamic_scene.h"
#include "fragg_map/cell_writer.h"
#include "fragg_map/errors.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/map.h"
#include "fragg_map/occupancy.h"
#include "same_map.h"
#include "state_masks_check.h"

namespace fragg {
namespace {

using test::kDynamicScenePersonY;

// The shared scene (dynamic_scene.h) under the surround rule.
MapParams dynamicParams(bool enabled, int known_radius_cells = 1) {
  return test::dynamicSceneParams(enabled, VoidSpaceRule::kSurround, known_radius_cells);
}
PointCloud sceneCloud(int person_y) { return test::dynamicSceneCloud(person_y); }
Eigen::Isometry3d sensorPose() { return test::dynamicScenePose(); }
Eigen::Vector3f cellCentre(int x, int y, int z) { return test::dynamicSceneCell(x, y, z); }

// Brute force: point i is dynamic when its cell is void (exactly at the lower clamp), or when it
// and every cell within r are free with confidence (log-odds <= seen_fx), in `ref` as it is now.
std::vector<uint8_t> referenceDynamic(const Map& ref, const PointCloud& cloud, int r,
                                      int16_t seen_fx) {
  const int16_t clamp_fx = ref.model().min_fx;
  auto seenFree = [&](const VoxelKey& k) {
    const Cell* c = ref.findCell(k);
    return c && c->observed() && c->log_odds_fx <= seen_fx;
  };
  std::vector<uint8_t> dynamic(cloud.size(), 0);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const VoxelKey k = ref.keyOf(sensorPose() * cloud.points_S[i].cast<double>());
    const Cell* c = ref.findCell(k);
    if (!seenFree(k)) continue;
    bool all = true;  // void, or free all around
    if (c->log_odds_fx != clamp_fx)
      for (int dz = -r; dz <= r; ++dz)
        for (int dy = -r; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx) all = all && seenFree({k.x + dx, k.y + dy, k.z + dz});
    dynamic[i] = all ? 1 : 0;
  }
  return dynamic;
}

// Brute force, the surround test: `marks` holds the scan alone (inserted into an empty map);
// a cell is seen free when the scan does not hit it and passes through it or it was known
// (occupied or free) in `ref` before the scan; a cell passes when every cell within r is seen
// free.
// (Seen-free flags are tabulated over the scene's box once a scan: the test stays cheap.)
class SurroundReference {
 public:
  SurroundReference(const Map& ref, const Map& marks) : ref_(ref), marks_(marks) {
    table_.resize(size_t{kX} * kY * kZ);
    for (int z = 0; z < kZ; ++z)
      for (int y = 0; y < kY; ++y)
        for (int x = 0; x < kX; ++x)
          table_[(static_cast<size_t>(z) * kY + y) * kX + x] = lookUp({x + kX0, y + kY0, z + kZ0});
  }
  bool surrounded(const VoxelKey& k, int r) const {
    for (int dz = -r; dz <= r; ++dz)
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
          if (!seenFree({k.x + dx, k.y + dy, k.z + dz})) return false;
    return true;
  }

 private:
  static constexpr int kX0 = -4, kY0 = -20, kZ0 = -14, kX = 50, kY = 41, kZ = 29;
  bool seenFree(const VoxelKey& n) const {
    const int x = n.x - kX0, y = n.y - kY0, z = n.z - kZ0;
    if (x < 0 || y < 0 || z < 0 || x >= kX || y >= kY || z >= kZ) return lookUp(n);
    return table_[(static_cast<size_t>(z) * kY + y) * kX + x];
  }
  bool lookUp(const VoxelKey& n) const {
    const Cell* m = marks_.findCell(n);
    if (m && m->observed()) return m->hits == 0;  // hit, or passed through
    const Cell* c = ref_.findCell(n);
    return c && ref_.state(*c) != CellState::kUnknown;
  }
  const Map& ref_;
  const Map& marks_;
  std::vector<char> table_;
};

TEST(DynamicMappingTest, BadOptionValuesAreRefused) {
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
  // A build without CUDA refuses the backend; with it, the option runs there (test/gpu).
  if (!builtWithCuda()) refused([](MapParams& p) { p.backend = Backend::kCuda; });
  refused([](MapParams& p) { p.dynamic.rule = static_cast<VoidSpaceRule>(2); });
  EXPECT_THROW((void)voidSpaceRuleFromString("sideways"), InvalidArgument);
  EXPECT_THROW((void)voidSpaceRuleFromString(""), InvalidArgument);
  EXPECT_THROW((void)voidSpaceRuleFromString("Surround"), InvalidArgument);
  for (VoidSpaceRule r : {VoidSpaceRule::kPassThrough, VoidSpaceRule::kSurround})
    EXPECT_EQ(voidSpaceRuleFromString(toString(r)), r);
  EXPECT_EQ(MapParams().dynamic.rule, VoidSpaceRule::kPassThrough);  // main's rule by default
  // Off, the values are not looked at (the default path is OctoMap's).
  MapParams off = dynamicParams(false);
  off.dynamic.void_probability = 0.0;
  EXPECT_NO_THROW(Map{off});
}

TEST(DynamicMappingTest, NothingVoidIntegratesAsWithTheOptionOff) {
  Map on(dynamicParams(true)), off(dynamicParams(false));
  const PointCloud cloud = sceneCloud(0);
  const InsertStats s_on = on.insert(cloud, sensorPose(), SensorModel::autoFromCloud());
  const InsertStats s_off = off.insert(cloud, sensorPose(), SensorModel::autoFromCloud());
  EXPECT_EQ(s_on.rays_dynamic, 0u);
  EXPECT_EQ(s_on.rays_hit, s_off.rays_hit);
  EXPECT_TRUE(on.lastDynamicPoints_S().empty());
  // The same cells in the same states; the only other difference: the cells the surround test
  // made void (at the clamp, below one miss's log-odds).
  const int16_t clamp_fx = on.model().min_fx;
  uint64_t cells = 0, made_void = 0;
  off.forEachBlock([&](const BlockKey& bk, const Block& block) {
    for (int ci = 0; ci < kCellsPerBlock; ++ci) {
      const Cell& o = block.cells[ci];
      const Cell* n = on.findCell(voxelKeyOf(bk, ci));
      ASSERT_NE(n, nullptr);
      ASSERT_EQ(n->observed(), o.observed());
      if (!o.observed()) continue;
      ++cells;
      EXPECT_EQ(on.state(*n), off.state(o));
      EXPECT_EQ(n->hits, o.hits);
      if (n->log_odds_fx == o.log_odds_fx) continue;
      EXPECT_EQ(n->log_odds_fx, clamp_fx);
      ++made_void;
    }
  });
  EXPECT_GT(made_void, 0u);
  EXPECT_LT(made_void, cells);
}

// The sequence through a map with the option on and through the brute-force reference, both
// with the neighbourhood radius `r`; checks every scan, returns the counts.
struct PersonRun {
  uint64_t dynamic_total = 0, static_dynamic = 0, free_but_static = 0, made_void = 0;
};

void walkPerson(int r, Map* out_map, PersonRun* run) {
  const MapParams params = dynamicParams(true, r);
  const int16_t seen_fx = logOddsFxOf(params.dynamic.void_probability);
  Map& map = *out_map;
  Map ref(dynamicParams(false));
  const int16_t clamp_fx = ref.model().min_fx;
  for (size_t step = 0; step < std::size(kDynamicScenePersonY); ++step) {
    const PointCloud cloud = sceneCloud(kDynamicScenePersonY[step]);
    const std::vector<uint8_t> expected = referenceDynamic(ref, cloud, r, seen_fx);
    for (size_t i = 0; i < cloud.size(); ++i) {
      run->static_dynamic += i < test::kDynamicSceneStaticPoints && expected[i] ? 1 : 0;
      // Points in confidently free cells that are not void stay static (the edge point).
      const Cell* c = ref.findCell(ref.keyOf(sensorPose() * cloud.points_S[i].cast<double>()));
      if (!expected[i] && c && c->observed() && c->log_odds_fx <= seen_fx) ++run->free_but_static;
    }
    PointCloud marked = cloud;
    marked.free_only.assign(expected.begin(), expected.end());
    // The scan's marks alone, and the surround test on the reference before the scan.
    Map marks(dynamicParams(false));
    marks.insert(marked, sensorPose(), SensorModel::autoFromCloud());
    struct Passed {
      VoxelKey key;
      Cell before;
      bool surrounded;
    };
    std::vector<Passed> passed;
    const SurroundReference surround(ref, marks);
    marks.forEachBlock([&](const BlockKey& bk, const Block& block) {
      for (int ci = 0; ci < kCellsPerBlock; ++ci) {
        const Cell& m = block.cells[ci];
        if (!m.observed() || m.hits > 0) continue;
        const VoxelKey k = voxelKeyOf(bk, ci);
        const Cell* before = ref.findCell(k);
        passed.push_back({k, before ? *before : Cell(), surround.surrounded(k, r)});
      }
    });
    ref.insert(marked, sensorPose(), SensorModel::autoFromCloud());
    ref.writeCells([&](CellWriter& w) {
      for (const Passed& p : passed) {
        Cell now = *ref.findCell(p.key);
        const bool was_void = p.before.observed() && p.before.log_odds_fx == clamp_fx;
        if (p.surrounded) {
          now.log_odds_fx = clamp_fx;
          run->made_void += was_void ? 0 : 1;
        } else if (!was_void && now.log_odds_fx <= clamp_fx) {
          now.log_odds_fx = static_cast<int16_t>(clamp_fx + 1);
        }
        w.set(p.key, now);
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
    run->dynamic_total += s.rays_dynamic;
  }
}

TEST(DynamicMappingTest, PersonWalkingThroughVoidSpaceMatchesBruteForce) {
  Map wide(dynamicParams(true, 2));
  PersonRun wide_run;
  walkPerson(2, &wide, &wide_run);  // the default radius: fewer cells qualify
  EXPECT_GT(wide_run.dynamic_total, 0u);
  Map map(dynamicParams(true, 1));
  PersonRun run;
  walkPerson(1, &map, &run);
  EXPECT_GE(run.dynamic_total, wide_run.dynamic_total);
  EXPECT_GT(run.dynamic_total, 50u);  // the person's columns, after the room became void
  EXPECT_EQ(run.static_dynamic + wide_run.static_dynamic, 0u);  // the floor and the wall
  EXPECT_GT(run.free_but_static, 0u);
  EXPECT_GE(run.made_void, 1000u);  // the room in front of the wall
  // No ghost: no cell of the person's path that the empty room's rays had cleared (y within
  // +-7.5 and z within -9..5 at x = 20, a cell's neighbours included) is occupied at the end.
  for (int y = -4; y <= 4; y += 4)
    for (int z = -8; z <= 4; ++z) {
      const Cell* c = map.findCell(map.keyOf(sensorPose() * cellCentre(20, y, z).cast<double>()));
      ASSERT_NE(c, nullptr);
      EXPECT_NE(map.state(*c), CellState::kOccupied) << y << " " << z;
    }
}

TEST(DynamicMappingTest, WithoutTheOptionThePersonLeavesATrail) {
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
