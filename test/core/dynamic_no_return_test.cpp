// No-return clearing for unorganised LiDAR clouds (SensorModel::lidar_beams with
// MapParams::clear_no_return_rays): a shuffled cloud of a 4-ring, 24-column LiDAR with beams
// missing, NaN and (0,0,0) no-return markers and jittered returns equals, cell for cell, a
// brute-force reference: the same returns plus a free-only point at twice max range along each
// beam no return falls in (bins found by an exhaustive nearest-angle search), inserted with the
// option off. Bad beam tables are refused with the field named and the map left as it was; the
// option leaves clouds without a table as they were; a kept scan with a table is not removable.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "same_map.h"

namespace fragg {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kMaxRangeM = 6.0;
constexpr uint32_t kColumns = 24;

LidarBeams beamTable() {
  LidarBeams b;
  b.ring_elevations_rad = {-10 * kDeg, -3 * kDeg, 4 * kDeg, 11 * kDeg};
  b.columns = kColumns;
  b.azimuth_offset_rad = 2 * kDeg;
  return b;
}

SensorModel lidar() {
  SensorModel m = SensorModel::spinningLidar(-15 * kDeg, 15 * kDeg, 0.1, kMaxRangeM);
  m.lidar_beams = beamTable();
  return m;
}

Eigen::Isometry3d pose() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(20 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.37, -0.21, 1.13);
  return T;
}

MapParams params(bool clear_no_return) {
  MapParams p;
  p.resolution_m = 0.1;
  p.backend = Backend::kCpu;
  p.threads = 2;
  p.clear_no_return_rays = clear_no_return;
  return p;
}

Eigen::Vector3f along(double elevation_rad, double azimuth_rad, double range_m) {
  return Eigen::Vector3d(std::cos(elevation_rad) * std::cos(azimuth_rad),
                         std::cos(elevation_rad) * std::sin(azimuth_rad), std::sin(elevation_rad))
             .cast<float>() *
         static_cast<float>(range_m);
}

// Returns jittered within their beam (up to 0.4 of a column step and of the smaller ring gap),
// beams with no point, NaN and (0,0,0) markers, two returns in one beam, and one point above
// the top ring by more than half a gap (in no bin); shuffled.
PointCloud unorganisedScan() {
  const LidarBeams b = beamTable();
  const double step = 2 * M_PI / kColumns;
  std::mt19937 rng(37);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4);
  PointCloud cloud;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (uint32_t r = 0; r < b.rings(); ++r)
    for (uint32_t c = 0; c < kColumns; ++c) {
      const uint32_t k = r * kColumns + c;
      if (k % 5 == 0) continue;  // dropped by the driver
      if (k % 7 == 1) {
        cloud.points_S.emplace_back(nan, nan, nan);
        continue;
      }
      if (k % 11 == 2) {
        cloud.points_S.emplace_back(0.f, 0.f, 0.f);
        continue;
      }
      const double el = b.ring_elevations_rad[r] + jitter(rng) * 6 * kDeg;
      const double az = b.azimuth_offset_rad + (c + jitter(rng)) * step;
      cloud.points_S.push_back(along(el, az, 2.0 + 0.1 * c + 0.3 * r));
      if (k % 9 == 3) cloud.points_S.push_back(along(el, az + 0.1 * step, 1.5));
    }
  cloud.points_S.push_back(along(14.9 * kDeg, 0.5, 3.0));  // 3.9 deg above the top ring
  std::shuffle(cloud.points_S.begin(), cloud.points_S.end(), rng);
  return cloud;
}

// Exhaustive: the bin of a return is the ring and column of least angular distance; a return
// farther than half a gap beyond an outer ring is in none.
std::vector<uint8_t> referenceReturned(const PointCloud& cloud, const LidarBeams& b) {
  std::vector<uint8_t> returned(size_t{b.rings()} * b.columns, 0);
  for (const Eigen::Vector3f& p : cloud.points_S) {
    if (!p.allFinite() || p.norm() == 0.f) continue;
    const double el = std::atan2(double(p.z()), std::hypot(double(p.x()), double(p.y())));
    const double az = std::atan2(double(p.y()), double(p.x()));
    int best_ring = -1;
    double best_el = 1e9;
    for (uint32_t r = 0; r < b.rings(); ++r) {
      const double d = std::fabs(el - b.ring_elevations_rad[r]);
      if (d < best_el) best_el = d, best_ring = int(r);
    }
    const auto& e = b.ring_elevations_rad;
    if (el > e.back() + 0.5 * (e.back() - e[e.size() - 2]) || el < e[0] - 0.5 * (e[1] - e[0]))
      continue;
    int best_col = -1;
    double best_az = 1e9;
    for (uint32_t c = 0; c < b.columns; ++c) {
      const double centre = b.azimuth_offset_rad + 2 * M_PI * c / b.columns;
      const double d = std::fabs(std::remainder(az - centre, 2 * M_PI));
      if (d < best_az) best_az = d, best_col = int(c);
    }
    returned[size_t(best_ring) * b.columns + best_col] = 1;
  }
  return returned;
}

TEST(NoReturnBeams, UnorganisedCloudEqualsFreeOnlyReference) {
  const PointCloud cloud = unorganisedScan();
  ASSERT_FALSE(cloud.organised());
  Map map(params(true));
  const InsertStats s = map.insert(cloud, pose(), lidar());

  const LidarBeams b = beamTable();
  const std::vector<uint8_t> returned = referenceReturned(cloud, b);
  PointCloud ref_cloud;
  for (const Eigen::Vector3f& p : cloud.points_S)
    if (p.allFinite() && p.norm() > 0.f) ref_cloud.points_S.push_back(p);
  ref_cloud.free_only.assign(ref_cloud.size(), 0);
  uint64_t empty = 0;
  for (uint32_t r = 0; r < b.rings(); ++r)
    for (uint32_t c = 0; c < b.columns; ++c) {
      if (returned[size_t(r) * b.columns + c]) continue;
      ++empty;
      const double az = b.azimuth_offset_rad + 2 * M_PI * c / b.columns;
      ref_cloud.points_S.push_back(along(b.ring_elevations_rad[r], az, 2 * kMaxRangeM));
      ref_cloud.free_only.push_back(1);
    }
  // 20 dropped, 14 NaN and 9 (0,0,0) of 96 beams: at least those are empty.
  EXPECT_GE(empty, 30u);
  EXPECT_EQ(s.rays_no_return, empty);
  Map ref(params(false));
  SensorModel plain = lidar();
  plain.lidar_beams = LidarBeams{};
  ref.insert(ref_cloud, pose(), plain);
  test::expectSameMap(map, ref, "beam table no-returns vs free-only reference");

  // A beam with no return clears free space out to max range; without the option it stays
  // unknown.
  Map off(params(false));
  off.insert(cloud, pose(), lidar());
  uint32_t r0 = 0, c0 = 0;
  while (returned[size_t(r0) * b.columns + c0]) (++c0 == b.columns) ? (c0 = 0, ++r0) : 0u;
  const Eigen::Vector3d far_m =
      pose() * along(b.ring_elevations_rad[r0], b.azimuth_offset_rad + 2 * M_PI * c0 / kColumns,
                     0.8 * kMaxRangeM)
                   .cast<double>();
  const Cell* cleared = map.findCell(map.keyOf(far_m));
  ASSERT_NE(cleared, nullptr);
  EXPECT_TRUE(cleared->observed());
  EXPECT_LT(cleared->log_odds_fx, 0);
  const Cell* untouched = off.findCell(off.keyOf(far_m));
  EXPECT_TRUE(untouched == nullptr || !untouched->observed());
}

TEST(NoReturnBeams, OptionOffOrNoTableLeavesTheMapAsBefore) {
  const PointCloud cloud = unorganisedScan();
  SensorModel plain = lidar();
  plain.lidar_beams = LidarBeams{};
  Map with_table_off(params(false)), no_table_on(params(true)), plain_off(params(false));
  with_table_off.insert(cloud, pose(), lidar());
  const InsertStats s = no_table_on.insert(cloud, pose(), plain);
  plain_off.insert(cloud, pose(), plain);
  EXPECT_EQ(s.rays_no_return, 0u);
  test::expectSameMap(with_table_off, plain_off, "table, option off");
  test::expectSameMap(no_table_on, plain_off, "option on, no table");
}

// The scan store keeps points, not the beam table: such a scan cannot be walked again, and
// removing it is refused with the map left as it was.
TEST(NoReturnBeams, KeptScanWithBeamTableIsNotRemovable) {
  MapParams p = params(true);
  p.scans.keep = true;
  Map map(p), before(p);
  const InsertStats s = map.insert(unorganisedScan(), pose(), lidar());
  before.insert(unorganisedScan(), pose(), lidar());
  EXPECT_GT(s.rays_no_return, 0u);
  EXPECT_THROW(map.remove(s.scan_id), InvalidArgument);
  test::expectSameMap(map, before, "after the refused removal");
}

TEST(NoReturnBeams, EvenlySpacedRingsSpanTheElevations) {
  const LidarBeams b = LidarBeams::evenlySpaced(32, 1024, -25 * kDeg, 15 * kDeg);
  ASSERT_EQ(b.rings(), 32u);
  EXPECT_DOUBLE_EQ(b.ring_elevations_rad.front(), -25 * kDeg);
  EXPECT_DOUBLE_EQ(b.ring_elevations_rad.back(), 15 * kDeg);
  EXPECT_EQ(b.ringOf(-25.6 * kDeg), 0);   // within half a gap (0.645 deg) below
  EXPECT_EQ(b.ringOf(-25.7 * kDeg), -1);  // beyond
  EXPECT_EQ(b.columnOf(-1e-9), 0u);
  EXPECT_EQ(b.columnOf(2 * M_PI * 1023.4 / 1024), 1023u);
  EXPECT_EQ(b.columnOf(2 * M_PI * 1023.6 / 1024), 0u);  // wraps
}

void expectRefused(const LidarBeams& beams, const std::string& field, SensorModel model = lidar()) {
  model.lidar_beams = beams;
  Map map(params(true));
  const PointCloud cloud = unorganisedScan();
  map.insert(cloud, pose(), lidar());
  Map before(params(true));
  before.insert(cloud, pose(), lidar());
  try {
    map.insert(cloud, Eigen::Isometry3d::Identity(), model);
    ADD_FAILURE() << "accepted a bad table, expected " << field;
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
  test::expectSameMap(map, before, field.c_str());
}

TEST(NoReturnBeams, BadBeamTablesRefused) {
  LidarBeams b = beamTable();
  b.columns = 0;
  expectRefused(b, "sensor.lidar_columns");
  b = beamTable();
  b.columns = kMaxLidarColumns + 1;
  expectRefused(b, "sensor.lidar_columns");
  b = LidarBeams{};
  b.columns = 16;  // columns without rings
  expectRefused(b, "sensor.lidar_columns");
  b = beamTable();
  std::swap(b.ring_elevations_rad[1], b.ring_elevations_rad[2]);  // not increasing
  expectRefused(b, "sensor.lidar_ring_elevations_rad");
  b = beamTable();
  b.ring_elevations_rad[2] = b.ring_elevations_rad[1];  // a ring twice
  expectRefused(b, "sensor.lidar_ring_elevations_rad");
  b = beamTable();
  b.ring_elevations_rad[0] = std::numeric_limits<double>::quiet_NaN();
  expectRefused(b, "sensor.lidar_ring_elevations_rad");
  b = beamTable();
  b.ring_elevations_rad.back() = 20 * kDeg;  // above the LiDAR's elevation_max (15 deg)
  expectRefused(b, "sensor.lidar_ring_elevations_rad");
  b = beamTable();
  b.azimuth_offset_rad = std::numeric_limits<double>::infinity();
  expectRefused(b, "sensor.lidar_azimuth_offset_rad");
  expectRefused(beamTable(), "sensor.lidar_rings",
                SensorModel::pinhole(60 * kDeg, 40 * kDeg, 0.1, kMaxRangeM));
  EXPECT_THROW(LidarBeams::evenlySpaced(0, 1024, -0.1, 0.1), InvalidArgument);
  EXPECT_THROW(LidarBeams::evenlySpaced(16, 1024, 0.1, -0.1), InvalidArgument);

  // With a height band the points left out would read as no returns: refused.
  MapParams banded = params(true);
  banded.height_filter.min_z_m = 0.0;
  banded.height_filter.max_z_m = 2.0;
  Map map(banded);
  EXPECT_THROW(map.insert(unorganisedScan(), pose(), lidar()), InvalidArgument);
  EXPECT_EQ(map.blockCount(), 0u);
}

}  // namespace
}  // namespace fragg
