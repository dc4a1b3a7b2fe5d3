// Finite points at the ends of the float range (issue 39): a huge coordinate with a tiny non-zero
// other one crashed the CPU backend (its DDA stepped an exhausted axis: a boundary parameter
// 0 * inf is NaN) and made the CUDA backend refuse the cloud. Checked here: the walk of such rays
// (whole and in pieces) stays a 6-connected path from the start cell to the end cell, and
// insertion of the points gives a map whose statistics account for every point, whose
// blocks lie within the max range, and whose other rays' cells are those of the cloud without
// them.
#include "extreme_points.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "fragg_map/internal/frustum_builder.h"
#include "fragg_map/internal/ray_prep.h"
#include "fragg_map/map.h"
#include "fragg_map/raycast.h"
#include "test_scenes.h"

namespace fragg {
namespace {

const std::vector<Eigen::Vector3f>& kExtremePoints = test::extremePoints();

struct Walk {
  std::vector<VoxelKey> cells;
  std::vector<bool> hits;
  void operator()(const VoxelKey& k, bool hit, int) {
    cells.push_back(k);
    hits.push_back(hit);
  }
};

/// The DDA's contract on one ray: starts in the start cell, every step moves one cell along one
/// axis towards the end cell, the hit (if any) is the end cell, and a hit ray visits
/// |dx| + |dy| + |dz| + 1 cells (a free-only ray one fewer).
void expectSixConnectedWalk(const RayVox& ray, const Walk& walk) {
  const VoxelKey start{ray.ref.x + floorToInt(ray.start_v[0]),
                       ray.ref.y + floorToInt(ray.start_v[1]),
                       ray.ref.z + floorToInt(ray.start_v[2])};
  const VoxelKey end{ray.ref.x + floorToInt(ray.end_v[0]), ray.ref.y + floorToInt(ray.end_v[1]),
                     ray.ref.z + floorToInt(ray.end_v[2])};
  const int steps = absInt(end.x - start.x) + absInt(end.y - start.y) + absInt(end.z - start.z);
  ASSERT_EQ(static_cast<int>(walk.cells.size()), steps + (ray.end_is_hit ? 1 : 0));
  if (walk.cells.empty()) return;
  EXPECT_EQ(walk.cells.front(), start);
  const int32_t lo[3] = {std::min(start.x, end.x), std::min(start.y, end.y),
                         std::min(start.z, end.z)};
  const int32_t hi[3] = {std::max(start.x, end.x), std::max(start.y, end.y),
                         std::max(start.z, end.z)};
  for (size_t i = 0; i < walk.cells.size(); ++i) {
    const VoxelKey& c = walk.cells[i];
    const int32_t k[3] = {c.x, c.y, c.z};
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(k[a], lo[a]) << "cell " << i << " axis " << a;
      EXPECT_LE(k[a], hi[a]) << "cell " << i << " axis " << a;
    }
    EXPECT_EQ(walk.hits[i], ray.end_is_hit && i + 1 == walk.cells.size()) << i;
    if (i == 0) continue;
    const VoxelKey& p = walk.cells[i - 1];
    EXPECT_EQ(absInt(c.x - p.x) + absInt(c.y - p.y) + absInt(c.z - p.z), 1) << "step " << i;
  }
  if (ray.end_is_hit) {
    EXPECT_EQ(walk.cells.back(), end);
  }
}

/// Start and end coordinates (voxel units, relative to the reference) that reach the DDA's
/// corner cases: denormals, spans whose reciprocal overflows a float, starts on a boundary.
std::vector<RayVox> cornerRays() {
  const float denorm = std::numeric_limits<float>::denorm_min();
  const std::vector<float> starts = {0.f, denorm, 3 * denorm, 1e-39f, 0.5f, 0.99999994f};
  const std::vector<float> offsets = {0.f,     denorm, -denorm, -2 * denorm, 1e-39f, -2.9e-39f,
                                      -1e-38f, 1e-30f, -1e-7f,  2.5f,        -7.25f, 40.f};
  std::vector<RayVox> rays;
  for (float s : starts)
    for (float dx : {10.5f, -3.2f, 0.f})
      for (float dy : offsets)
        for (float dz : offsets)
          for (bool hit : {true, false}) {
            RayVox r;
            r.ref = VoxelKey{100, -200, 300};
            for (int a = 0; a < 3; ++a) r.start_v[a] = s;
            r.end_v[0] = s + dx;
            r.end_v[1] = -dy;  // ends just below the boundary the start lies on, or past it
            r.end_v[2] = s + dz;
            r.end_is_hit = hit;
            rays.push_back(r);
          }
  return rays;
}

TEST(ExtremeRays, EveryWalkIsASixConnectedPathToTheEndCell) {
  for (const RayVox& ray : cornerRays()) {
    SCOPED_TRACE(::testing::Message() << "start " << ray.start_v[0] << " end " << ray.end_v[0]
                                      << " " << ray.end_v[1] << " " << ray.end_v[2]);
    Walk walk;
    const int visited = traverseDda(ray, walk);
    EXPECT_EQ(visited, static_cast<int>(walk.cells.size()));
    expectSixConnectedWalk(ray, walk);
  }
}

TEST(ExtremeRays, PiecesLaidEndToEndAreTheWholeWalk) {
  // The CUDA ray pass cuts long rays into pieces of the major axis's steps; the same cut on the
  // host must give the whole walk for these rays too.
  for (const RayVox& ray : cornerRays()) {
    Walk whole;
    traverseDda(ray, whole);
    const int major = ddaMajorSteps(ray);
    for (int len : {1, 2, 5}) {
      Walk pieces;
      for (int first = 0; first == 0 || first < major; first += len) {
        DdaPiece piece;
        piece.first_major = first;
        piece.end_major = first + len;
        traverseDdaPiece(ray, piece, pieces);
      }
      ASSERT_EQ(pieces.cells, whole.cells) << "pieces of " << len << ", end " << ray.end_v[0] << " "
                                           << ray.end_v[1] << " " << ray.end_v[2];
    }
  }
}

TEST(ExtremeRays, BresenhamStaysBetweenItsEnds) {
  for (const RayVox& ray : cornerRays()) {
    Walk walk;
    traverseBresenham(ray, walk);
    for (const VoxelKey& c : walk.cells) {
      EXPECT_GE(c.y, ray.ref.y + std::min(floorToInt(ray.start_v[1]), floorToInt(ray.end_v[1])));
      EXPECT_LE(c.y, ray.ref.y + std::max(floorToInt(ray.start_v[1]), floorToInt(ray.end_v[1])));
    }
  }
}

// A wall 3 m ahead (x), 10 cm apart: rays that share no cell with the extreme points' rays
// beyond the sensor's neighbourhood.
PointCloud wallCloud() {
  PointCloud c;
  for (int i = -10; i <= 10; ++i)
    for (int j = -5; j <= 5; ++j) c.points_S.emplace_back(3.0f, 0.1f * i, 0.1f * j);
  return c;
}

MapParams cpuParams(double resolution_m) {
  MapParams p;
  p.backend = Backend::kCpu;
  p.threads = 2;
  p.resolution_m = resolution_m;
  return p;
}

TEST(ExtremePoints, InsertionAccountsForEveryPointAndKeepsTheOtherRays) {
  // The sensor at the origin: its start lies on cell boundaries, as in the user's report.
  const Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  for (double res : {0.05, 0.2}) {
    for (double max_range_m : {20.0, 80.0, -1.0}) {
      const SensorModel sensor = SensorModel::autoFromCloud(0.0, max_range_m);
      Map wall_only(cpuParams(res));
      wall_only.insert(wallCloud(), T_map_sensor, sensor);
      for (const Eigen::Vector3f& p : kExtremePoints) {
        SCOPED_TRACE(::testing::Message() << "point " << p.transpose() << " res " << res
                                          << " max range " << max_range_m);
        PointCloud cloud = wallCloud();
        cloud.points_S.push_back(p);
        Map map(cpuParams(res));
        const InsertStats s = map.insert(cloud, T_map_sensor, sensor);
        EXPECT_EQ(s.points_in, cloud.size());
        EXPECT_EQ(s.rays_hit + s.rays_free_only + s.dropped_invalid + s.dropped_min_range,
                  cloud.size());
        EXPECT_GE(s.rays_hit, wallCloud().size());
        // An accepted hit marks the point's own cell (1e-45 m: the sensor's cell).
        bool has_hit = s.rays_hit > wallCloud().size();
        const VoxelKey hit_key =
            has_hit ? map.keyOf(T_map_sensor * p.cast<double>()) : VoxelKey{0, 0, 0};
        // Every other cell of the wall's map is in this map, with the same value: the extreme
        // ray adds cells (free ones near the sensor, or a clipped free-only ray) and takes none.
        size_t compared = 0;
        wall_only.forEachBlock([&](const BlockKey& key, const Block& block) {
          const Block* other = map.findBlock(key);
          ASSERT_NE(other, nullptr);
          for (int c = 0; c < kCellsPerBlock; ++c) {
            if (!block.cells[c].observed()) continue;
            if (has_hit && key == blockKeyOf(hit_key) && c == cellIndexOf(hit_key)) continue;
            ++compared;
            EXPECT_EQ(other->cells[c].log_odds_fx, block.cells[c].log_odds_fx) << c;
            EXPECT_EQ(other->cells[c].hits, block.cells[c].hits) << c;
          }
        });
        EXPECT_GT(compared, 0u);
        // The map's reach: the used max range from the sensor (an unlimited range resolves to
        // the farthest point that gives a ray), plus a block.
        const double reach_m = s.sensor.max_range_m + 2.0 * std::sqrt(3.0) * 8.0 * res;
        map.forEachBlock([&](const BlockKey& key, const Block&) {
          const Eigen::Vector3d centre =
              (Eigen::Vector3d(key.x, key.y, key.z).array() + 0.5).matrix() * 8.0 * res;
          EXPECT_LE((centre - T_map_sensor.translation()).norm(), reach_m);
        });
      }
    }
  }
}

TEST(ExtremePoints, DdaAndBresenhamAndRemovalSurviveThem) {
  // Both ray casters, and a kept scan taken out again: the map returns to the wall's.
  for (RayCast caster : {RayCast::kDda, RayCast::kBresenham}) {
    MapParams p = cpuParams(0.05);
    p.raycast = caster;
    p.scans.keep = true;
    Map map(p);
    const SensorModel sensor = SensorModel::autoFromCloud(0.0, 20.0);
    map.insert(wallCloud(), Eigen::Isometry3d::Identity(), sensor);
    const size_t known = map.knownVoxelCount();
    PointCloud extreme;
    extreme.points_S = kExtremePoints;
    const InsertStats s = map.insert(extreme, Eigen::Isometry3d::Identity(), sensor);
    EXPECT_EQ(s.points_in, kExtremePoints.size());
    map.remove(s.scan_id);
    EXPECT_EQ(map.knownVoxelCount(), known);
  }
}

TEST(ExtremePoints, RaysBeyondFloatPrecisionAreDroppedAsInvalid) {
  // 2^24 voxels from the sensor is the farthest a ray's end may lie (kMaxRayV): at 1 m,
  // 16,777 km, inside the key range.
  Map map(cpuParams(1.0));
  PointCloud cloud;
  cloud.points_S = {{3e7f, 0.f, 0.f}, {0.f, -2e7f, 0.f}, {1.f, 2.f, 0.5f}};
  const InsertStats s =
      map.insert(cloud, Eigen::Isometry3d::Identity(), SensorModel::autoFromCloud(0.0, -1.0));
  EXPECT_EQ(s.dropped_invalid, 2u);
  EXPECT_EQ(s.rays_hit, 1u);
}

TEST(ExtremePoints, FrustumOfAnUnlimitedRangeStaysInTheKeyRange) {
  // Found by the insertion fuzzer (UBSan: float-cast-overflow in buildFrustum): without a max
  // range the auto model's range is the farthest point's (here 5.2e27 m), whose box in blocks
  // does not fit int32. The box is the whole key range instead: lo <= the sensor's block <= hi.
  for (SensorModel model : {SensorModel::spinningLidar(-0.5, 0.5, 0.0, 5.2e27),
                            SensorModel::pinhole(1.5, 1.0, 0.0, 3.4e38)}) {
    const Frustum f = buildFrustum(model, Eigen::Isometry3d::Identity(), 0.05);
    EXPECT_EQ(f.aabb_min.x, -(1 << 28));
    EXPECT_EQ(f.aabb_max.x, (1 << 28) - 1);
    EXPECT_LE(f.aabb_min.z, 0);
    EXPECT_GE(f.aabb_max.z, 0);
  }
}

}  // namespace
}  // namespace fragg
