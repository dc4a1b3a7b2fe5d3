// Frontier queries at LiDAR scale (issue 34 item 5): the coverage gain against a brute-force
// visibility count, every cluster's viewpoints in one batch against one cluster at a time, the
// coarse copy of a box against the coarse copy of the whole map, and the beam spacing of
// simulated LiDAR clouds against the spacing they were made with.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/planning/beam_spacing.h"
#include "fragg_map/planning/coarse_map.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/viewpoints.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/scene.h"
#include "planning/collision_reference.h"

namespace fragg::planning::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A free hall 6 x 4 x 1.2 m at 0.1 m with two occupied pillars and a few unknown pockets;
// unknown beyond. Its frontier cells line the hall's faces and the pockets.
Map hallMap() {
  MapParams p;
  p.resolution_m = 0.1;
  Map map(p);
  map.writeCells([&](CellWriter& w) {
    for (int z = -6; z < 6; ++z)
      for (int y = -20; y < 20; ++y)
        for (int x = -30; x < 30; ++x) {
          const bool pillar = (std::abs(x - 8) <= 1 && std::abs(y - 3) <= 1) ||
                              (std::abs(x + 12) <= 2 && std::abs(y + 6) <= 1 && z < 2);
          const bool pocket = (std::abs(x - 20) <= 1 && std::abs(y + 10) <= 2 && z > 2) ||
                              (std::abs(x + 3) <= 1 && std::abs(y - 14) <= 1);
          if (pocket) continue;  // never observed
          w.set({x, y, z}, pillar ? Cell{1, 3000} : Cell{0, -2000});
        }
  });
  return map;
}

// Brute-force coverage: a cluster cell counts when its centre is within range and inside the
// field of view (angles from atan2), and every cell a fine sampling of the segment from the
// viewpoint to that centre passes through, other than the cell itself, is free.
double bruteForceCoverage(const Map& map, const FrontierCluster& cluster,
                          const Eigen::Vector3d& from_m, double yaw, const GainSensor& s) {
  double seen = 0.0;
  const Eigen::Matrix3d R_map_sensor =
      Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (const VoxelKey& k : cluster.cells) {
    const Eigen::Vector3d to_m = map.centerOf(k);
    const Eigen::Vector3d d_S = R_map_sensor.transpose() * (to_m - from_m);
    if (d_S.norm() > s.max_range_m) continue;
    if (s.kind == GainSensor::Kind::kPinhole) {
      if (d_S.x() <= 0.0 || std::abs(std::atan(d_S.y() / d_S.x())) > 0.5 * s.horizontal_fov_rad ||
          std::abs(std::atan(d_S.z() / d_S.x())) > 0.5 * s.vertical_fov_rad)
        continue;
    } else {
      const double el = std::atan2(d_S.z(), std::hypot(d_S.x(), d_S.y()));
      if (el < s.min_elevation_rad || el > s.max_elevation_rad) continue;
    }
    const double length = (to_m - from_m).norm();
    const double step = map.resolution() / 200.0;
    bool clear = true;
    for (double t = 0.0; t < length && clear; t += step) {
      const VoxelKey c = map.keyOf(from_m + (to_m - from_m) * (t / length));
      if (c == k) break;
      const Cell* cell = map.findCell(c);
      clear = cell && map.state(*cell) == CellState::kFree;
    }
    if (clear) seen += 1.0;
  }
  return seen;
}

TEST(CoverageGain, MatchesBruteForceVisibility) {
  const Map map = hallMap();
  const std::vector<FrontierCluster> clusters =
      FrontierClusterer().cluster(map, findFrontierCells(map));
  ASSERT_GE(clusters.size(), 3u);
  ViewpointOptions o;
  o.gain = ViewpointGain::kCoverage;
  o.radii_m = {1.3};
  o.angles = 7;
  o.clearance_m = 0.0;
  o.top_k = 100;  // every candidate with a gain
  o.sensor.max_range_m = 4.0;
  size_t compared = 0, exact = 0, partly_hidden = 0;
  for (const GainSensor::Kind kind : {GainSensor::Kind::kPinhole, GainSensor::Kind::kLidar}) {
    o.sensor.kind = kind;
    const auto views = clustersViewpoints(map, clusters, o, 2);
    ASSERT_EQ(views.size(), clusters.size());
    for (size_t i = 0; i < clusters.size(); ++i)
      for (const Viewpoint& v : views[i]) {
        const double expected =
            bruteForceCoverage(map, clusters[i], v.position_m, v.yaw_rad, o.sensor);
        // Sampling can miss a cell a segment only clips at a corner (and so see a cell the
        // exact walk finds hidden), never hide one the walk sees.
        ASSERT_LE(v.gain_bits, expected) << "cluster " << i << " at " << v.position_m.transpose();
        ASSERT_GE(v.gain_bits, 0.995 * expected - 1.0) << "cluster " << i;
        EXPECT_EQ(
            coverageGainCells(map, map.blockView(), clusters[i], v.position_m, v.yaw_rad, o.sensor),
            v.gain_bits);
        ++compared;
        if (v.gain_bits == expected) ++exact;
        if (expected < double(clusters[i].cells.size())) ++partly_hidden;
      }
  }
  EXPECT_GT(compared, 30u);
  EXPECT_GE(exact, compared * 9 / 10);
  EXPECT_GT(partly_hidden, 10u) << "the pillars, the field of view and the range hide cells";
}

// clustersViewpoints over all clusters equals clusterViewpoints one cluster at a time, with
// either gain, a robot position and the clearance check.
TEST(CoverageGain, BatchEqualsOneClusterAtATime) {
  const Map map = hallMap();
  const std::vector<FrontierCluster> clusters =
      FrontierClusterer().cluster(map, findFrontierCells(map));
  for (const ViewpointGain gain : {ViewpointGain::kEntropy, ViewpointGain::kCoverage}) {
    ViewpointOptions o;
    o.gain = gain;
    o.radii_m = {0.8, 1.5};
    o.clearance_m = 0.15;
    o.top_k = 4;
    o.sensor.columns = 24;
    o.sensor.rows = 16;
    o.sensor.max_range_m = 3.0;
    o.robot_m = Eigen::Vector3d(0.5, -0.3, 0.0);
    const auto all = clustersViewpoints(map, clusters, o, 2);
    ASSERT_EQ(all.size(), clusters.size());
    size_t with_views = 0;
    for (size_t i = 0; i < clusters.size(); ++i) {
      const auto one = clusterViewpoints(map, clusters[i], o);
      ASSERT_EQ(all[i].size(), one.size()) << viewpointGainName(gain) << " cluster " << i;
      for (size_t j = 0; j < one.size(); ++j) {
        EXPECT_EQ(all[i][j].position_m, one[j].position_m);
        EXPECT_EQ(all[i][j].gain_bits, one[j].gain_bits);
        EXPECT_EQ(all[i][j].score, one[j].score);
      }
      with_views += one.empty() ? 0 : 1;
    }
    EXPECT_GT(with_views, 2u) << viewpointGainName(gain);
  }
  EXPECT_EQ(viewpointGainFromName("coverage"), ViewpointGain::kCoverage);
  EXPECT_EQ(viewpointGainFromName("entropy"), ViewpointGain::kEntropy);
  EXPECT_THROW((void)viewpointGainFromName("bits"), InvalidArgument);
  std::atomic<bool> cancel{true};
  QueryControl cancelled;
  cancelled.cancel = &cancel;
  ViewpointOptions o;
  EXPECT_THROW((void)clustersViewpoints(map, clusters, o, 0, &cancelled), QueryStopped);
  EXPECT_THROW((void)clustersViewpoints(map, clusters, o, -1), InvalidArgument);
}

// The coarse copy of a box answers a query in that box as the copy of the whole map does:
// the same frontier cells, clusters and viewpoints.
TEST(CoarseFrontiers, BoxCopyAnswersAsTheWholeCopy) {
  const Map map = randomMap(0.1, 40, 21);
  FrontierFilter box;
  box.use_box = true;
  box.box_min_m = Eigen::Vector3d(-2.2, -1.3, -0.9);
  box.box_max_m = Eigen::Vector3d(2.6, 2.9, 1.7);  // into the corner without blocks
  ViewpointOptions o;
  o.gain = ViewpointGain::kCoverage;
  o.radii_m = {0.6, 1.2};
  o.clearance_m = 0.0;
  o.top_k = 3;
  o.sensor.max_range_m = 3.0;
  for (const int k : {2, 4}) {
    const Map whole = coarseStateMap(map, k);
    const Map part = coarseStateMapIn(map, k, box.box_min_m, box.box_max_m, viewpointReachM(o));
    EXPECT_LT(part.blockCount(), whole.blockCount()) << k;
    const auto cells = findFrontierCells(whole, box);
    ASSERT_GT(cells.size(), 20u) << k;
    EXPECT_EQ(findFrontierCells(part, box), cells) << k;
    const auto clusters = FrontierClusterer({2, 3.0}).cluster(whole, cells);
    const auto expected = clustersViewpoints(whole, clusters, o, 1);
    const auto got = clustersViewpoints(part, clusters, o, 1);
    size_t views = 0;
    for (size_t i = 0; i < clusters.size(); ++i) {
      ASSERT_EQ(got[i].size(), expected[i].size()) << k << " cluster " << i;
      for (size_t j = 0; j < got[i].size(); ++j) {
        EXPECT_EQ(got[i][j].position_m, expected[i][j].position_m);
        EXPECT_EQ(got[i][j].gain_bits, expected[i][j].gain_bits);
      }
      views += got[i].size();
    }
    EXPECT_GT(views, 0u) << k;
  }
  EXPECT_THROW((void)coarseStateMapIn(map, 4, box.box_max_m, box.box_min_m, 0.0), InvalidArgument);
  EXPECT_THROW((void)coarseStateMapIn(map, 4, box.box_min_m, box.box_max_m, -1.0), InvalidArgument);
  EXPECT_THROW((void)coarseStateMapIn(map, 3, box.box_min_m, box.box_max_m, 0.0), InvalidArgument);
}

// Simulated spinning LiDARs in the campus scene: the estimate is the spacing they were made
// with (beams evenly spread), with returns dropped and range noise; the far range is near the
// sensor's reach. Too few points, or none, give no estimate.
// The campus scene's mesh and a LiDAR pose in it (-30, 0, 2.7), for the beam-spacing tests.
struct CampusLidar {
  CampusLidar()
      : bvh(sim::loadScene(std::string(FRAGG_SOURCE_DIR) + "/config/scenes/campus.json").mesh) {
    T.translation() = Eigen::Vector3d(-30.0, 0.0, 2.7);
  }
  geometry::MeshBvh bvh;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
};

TEST(BeamSpacing, OfSimulatedLidars) {
  const CampusLidar campus;
  const geometry::MeshBvh& bvh = campus.bvh;
  const Eigen::Isometry3d& T = campus.T;
  BeamSpacingTracker tracker;
  for (const int beams : {32, 64, 128}) {
    sim::LidarSpec spec;
    spec.beams = beams;
    spec.azimuth_steps = 1800;
    spec.elevation_min_deg = -25.0;
    spec.elevation_max_deg = 15.0;
    spec.max_range_m = 80.0;
    spec.range_noise_m = 0.02;
    spec.dropout = 0.2;
    const PointCloud cloud = sim::simulateLidar(bvh, spec, T, 7, uint64_t(beams));
    const auto b = estimateBeamSpacing(cloud.points_S);
    ASSERT_TRUE(b.has_value()) << beams;
    const double want = 40.0 / (beams - 1) * kPi / 180.0;
    EXPECT_NEAR(b->angle_rad, want, 0.03 * want) << beams;
    EXPECT_GT(b->range_m, 20.0) << beams;
    EXPECT_LE(b->range_m, 80.5) << beams;
    tracker.add(*b);
  }
  ASSERT_TRUE(tracker.estimate().has_value());
  EXPECT_NEAR(tracker.estimate()->angle_rad, 40.0 / 63 * kPi / 180.0,
              0.03 * 40.0 / 63 * kPi / 180.0)
      << "the median of three";
  EXPECT_TRUE(tracker.wantsMore());
  for (int i = 0; i < 5; ++i) tracker.add(BeamSpacing{1.0, 1.0});
  EXPECT_FALSE(tracker.wantsMore());
  EXPECT_LT(tracker.estimate()->angle_rad, 0.5) << "later clouds are not looked at";

  EXPECT_FALSE(estimateBeamSpacing({}).has_value());
  std::vector<Eigen::Vector3f> few(500, Eigen::Vector3f(5.0f, 1.0f, 0.5f));
  EXPECT_FALSE(estimateBeamSpacing(few).has_value());
  std::vector<Eigen::Vector3f> nan(5000, Eigen::Vector3f::Constant(NAN));
  EXPECT_FALSE(estimateBeamSpacing(nan).has_value());
  EXPECT_FALSE(BeamSpacingTracker().estimate().has_value());
}

// The estimate against a plain reference on the same samples: every stride-th point with a
// finite position, 1 m away or more, sorted by (azimuth wedge of 1 degree, elevation); the
// median of the steps between neighbours of a wedge that are 0.02 degrees apart or more; the
// 99th-percentile range. The estimate (samples in parallel, a sort per wedge) gives the same
// doubles, with NaNs and points too near mixed in.
TEST(BeamSpacing, EqualsAPlainSortOfTheSamePoints) {
  const CampusLidar campus;
  sim::LidarSpec spec;
  spec.beams = 128;
  spec.azimuth_steps = 1406;
  spec.max_range_m = 60.0;
  spec.range_noise_m = 0.02;
  spec.dropout = 0.1;
  std::vector<Eigen::Vector3f> points =
      sim::simulateLidar(campus.bvh, spec, campus.T, 3, 11).points_S;
  for (size_t i = 0; i < points.size(); i += 101) points[i] = Eigen::Vector3f::Constant(NAN);
  for (size_t i = 50; i < points.size(); i += 211) points[i] = Eigen::Vector3f(0.3f, 0.2f, 0.1f);
  ASSERT_GT(points.size(), size_t{60000});

  const size_t stride = std::max<size_t>(1, points.size() / 60000);
  std::vector<std::pair<int32_t, double>> samples;
  std::vector<double> ranges;
  for (size_t i = 0; i < points.size(); i += stride) {
    const Eigen::Vector3d p = points[i].cast<double>();
    if (!p.allFinite()) continue;
    const double horizontal = std::hypot(p.x(), p.y()), range = p.norm();
    if (range < 1.0 || horizontal <= 0.0) continue;
    samples.emplace_back(int32_t((std::atan2(p.y(), p.x()) + kPi) / (kPi / 180.0)),
                         std::atan2(p.z(), horizontal));
    ranges.push_back(range);
  }
  std::sort(samples.begin(), samples.end());
  std::vector<double> steps;
  for (size_t i = 1; i < samples.size(); ++i) {
    if (samples[i].first != samples[i - 1].first) continue;
    const double step = samples[i].second - samples[i - 1].second;
    if (step >= 0.02 * (kPi / 180.0)) steps.push_back(step);
  }
  std::nth_element(steps.begin(), steps.begin() + ptrdiff_t(steps.size() / 2), steps.end());
  const size_t far = std::min(ranges.size() - 1, size_t(0.99 * double(ranges.size())));
  std::nth_element(ranges.begin(), ranges.begin() + ptrdiff_t(far), ranges.end());

  const auto b = estimateBeamSpacing(points);
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->angle_rad, steps[steps.size() / 2]);
  EXPECT_EQ(b->range_m, ranges[far]);
}

}  // namespace
}  // namespace fragg::planning::test
