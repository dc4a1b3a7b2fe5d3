// The auto sensor model's statistics (internal/auto_sensor.h): the same bits whatever the
// points' order and the thread count (what lets the CUDA backend gather them on the device),
// and the values of a plain pass over the points.
#include "fragg_map/internal/auto_sensor.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace fragg {
namespace {

/// A cloud with every kind of point the statistics meet: a depth camera's frustum, points all
/// around (a LiDAR's), invalid ones (NaN, +-Inf, the origin) and z = -0.
PointCloud mixedCloud(uint32_t seed, size_t n, bool camera_only) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f), depth(0.3f, 8.f);
  PointCloud c;
  for (size_t i = 0; i < n; ++i) {
    const size_t kind = i % 101;
    if (kind == 3) {
      c.points_S.emplace_back(std::nanf(""), 1.f, 2.f);
    } else if (kind == 5) {
      c.points_S.emplace_back(1.f, std::numeric_limits<float>::infinity(), 2.f);
    } else if (kind == 7) {
      c.points_S.emplace_back(0.f, 0.f, 0.f);
    } else if (kind == 11 && !camera_only) {
      c.points_S.emplace_back(u(rng) * 5.f, u(rng) * 5.f, -0.f);
    } else if (camera_only || kind % 2 == 0) {
      const float z = depth(rng);
      c.points_S.emplace_back(u(rng) * 0.55f * z, u(rng) * 0.4f * z, z);
    } else {
      c.points_S.emplace_back(u(rng) * 30.f, u(rng) * 30.f, u(rng) * 3.f);
    }
  }
  return c;
}

/// Bit patterns: 0.0 and -0.0 differ, as they would for a memcmp of the device's result.
uint64_t bits(double v) {
  uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

void expectSameBits(const AutoSensorStats& a, const AutoSensorStats& b) {
  EXPECT_EQ(bits(a.max_dist_m), bits(b.max_dist_m));
  EXPECT_EQ(bits(a.sin_min), bits(b.sin_min));
  EXPECT_EQ(bits(a.sin_max), bits(b.sin_max));
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.dir_sum_fx[i], b.dir_sum_fx[i]) << i;
  EXPECT_EQ(a.valid, b.valid);
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(a.fit[k].fits, b.fit[k].fits) << k;
    EXPECT_EQ(bits(a.fit[k].tan_h), bits(b.fit[k].tan_h)) << k;
    EXPECT_EQ(bits(a.fit[k].tan_v), bits(b.fit[k].tan_v)) << k;
  }
}

TEST(AutoSensorStats, SameBitsInAnyOrderAndOnAnyThreadCount) {
  for (bool camera_only : {true, false}) {
    const PointCloud cloud = mixedCloud(7, 20011, camera_only);
    const AutoSensorStats ref = gatherAutoSensorStats(cloud);
    PointCloud shuffled = cloud;
    std::shuffle(shuffled.points_S.begin(), shuffled.points_S.end(), std::mt19937(3));
    expectSameBits(gatherAutoSensorStats(shuffled), ref);
    PointCloud reversed = cloud;
    std::reverse(reversed.points_S.begin(), reversed.points_S.end());
    expectSameBits(gatherAutoSensorStats(reversed), ref);
    const int threads = omp_get_max_threads();
    for (int t : {1, 3}) {
      omp_set_num_threads(t);
      expectSameBits(gatherAutoSensorStats(shuffled), ref);
    }
    omp_set_num_threads(threads);
    // Gathered one point at a time and merged in any grouping: the same bits too (how the
    // device reduces its threads' statistics).
    AutoSensorStats one_by_one;
    for (size_t i = cloud.size(); i-- > 0;) {
      AutoSensorStats p;
      const Eigen::Vector3f& q = cloud.points_S[i];
      addAutoSensorPoint(q.x(), q.y(), q.z(), sensorAxisTable(), p);
      one_by_one.merge(p);
    }
    expectSameBits(one_by_one, ref);
  }
}

TEST(AutoSensorStats, ValuesOfAPlainPassOverThePoints) {
  // Reference: plain double arithmetic, dividing for every tangent; the direction sum in
  // floating point (the fixed-point sum is within half a unit of 2^-32 per point of it).
  for (bool camera_only : {true, false}) {
    const PointCloud cloud = mixedCloud(11, 5003, camera_only);
    const AutoSensorStats s = gatherAutoSensorStats(cloud);
    uint64_t valid = 0;
    double max_dist = 0, sin_min = 1, sin_max = -1;
    Eigen::Vector3d dir = Eigen::Vector3d::Zero();
    bool fits[6] = {true, true, true, true, true, true};
    double tan_h[6] = {}, tan_v[6] = {};
    const SensorAxisTable& axes = sensorAxisTable();
    for (const Eigen::Vector3f& p : cloud.points_S) {
      if (!p.allFinite() || p.squaredNorm() == 0.f) continue;
      ++valid;
      const Eigen::Vector3d d = p.cast<double>();
      const double r = d.norm();
      max_dist = std::max(max_dist, r);
      dir += d / r;
      sin_min = std::min(sin_min, d.z() / r);
      sin_max = std::max(sin_max, d.z() / r);
      for (int k = 0; k < 6; ++k) {
        const double z = axes.sign[k] * d[axes.along[k]];
        if (z <= std::cos(85 * M_PI / 180) * r) fits[k] = false;
        if (!fits[k]) continue;
        tan_h[k] = std::max(tan_h[k], std::fabs(d[axes.across_h[k]]) / z);
        tan_v[k] = std::max(tan_v[k], std::fabs(d[axes.across_v[k]]) / z);
      }
    }
    EXPECT_EQ(s.valid, valid);
    EXPECT_EQ(valid, cloud.size() - 3 * ((cloud.size() + 100) / 101));
    EXPECT_NEAR(s.max_dist_m, max_dist, 1e-12 * max_dist);
    EXPECT_NEAR(s.sin_min, sin_min, 1e-15);
    EXPECT_NEAR(s.sin_max, sin_max, 1e-15);
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(double(s.dir_sum_fx[a]) / kAutoDirFixedScale, dir[a], 1e-9 * valid) << a;
    for (int k = 0; k < 6; ++k) {
      EXPECT_EQ(s.fit[k].fits != 0, fits[k]) << k;
      if (!fits[k]) {
        EXPECT_EQ(s.fit[k].tan_h, 0.0) << k;
        EXPECT_EQ(s.fit[k].tan_v, 0.0) << k;
        continue;
      }
      EXPECT_EQ(s.fit[k].tan_h, tan_h[k]) << k;  // the same maximum, to the bit
      EXPECT_EQ(s.fit[k].tan_v, tan_v[k]) << k;
    }
    // A camera cloud fits +z only (x right, y down: its basis reads x, then y).
    if (camera_only) {
      EXPECT_TRUE(s.fit[4].fits);
      EXPECT_EQ(axes.across_h[4], 0);
      EXPECT_EQ(axes.across_v[4], 1);
      for (int k : {0, 1, 2, 3, 5}) EXPECT_FALSE(s.fit[k].fits) << k;
    }
  }
}

TEST(AutoSensorStats, NegativeZeroElevationReadsAsPositiveZero) {
  PointCloud c;
  c.points_S.emplace_back(3.f, 4.f, -0.f);
  const AutoSensorStats s = gatherAutoSensorStats(c);
  EXPECT_EQ(bits(s.sin_min), bits(0.0));
  EXPECT_EQ(bits(s.sin_max), bits(0.0));
  EXPECT_EQ(s.max_dist_m, 5.0);
  // 3 / 5 and 4 / 5 x 2^32, truncated (what float 3 and 4 over double 5 give).
  EXPECT_EQ(s.dir_sum_fx[0], static_cast<int64_t>(3.0 * (1.0 / 5.0 * kAutoDirFixedScale)));
  EXPECT_EQ(s.dir_sum_fx[1], static_cast<int64_t>(4.0 * (1.0 / 5.0 * kAutoDirFixedScale)));
  EXPECT_NEAR(double(s.dir_sum_fx[0]), 0.6 * kAutoDirFixedScale, 1.0);
  EXPECT_NEAR(double(s.dir_sum_fx[1]), 0.8 * kAutoDirFixedScale, 1.0);
  EXPECT_EQ(s.dir_sum_fx[2], 0);
}

TEST(AutoSensorStats, NoValidPointGivesTheWholeSphere) {
  PointCloud c;
  c.points_S.emplace_back(0.f, 0.f, 0.f);
  c.points_S.emplace_back(std::nanf(""), 0.f, 0.f);
  const AutoSensorStats s = gatherAutoSensorStats(c);
  EXPECT_EQ(s.valid, 0u);
  const SensorModel m = resolveAutoSensor(SensorModel::autoFromCloud(), c, s);
  EXPECT_EQ(m.type, SensorType::kSpinningLidar);
  EXPECT_EQ(m.elevation_min_rad, -M_PI / 2);
  EXPECT_EQ(m.elevation_max_rad, M_PI / 2);
  EXPECT_EQ(m.max_range_m, 1.0);
}

}  // namespace
}  // namespace fragg
