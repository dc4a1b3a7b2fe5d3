// The device's accumulators of the auto sensor model's statistics (cuda/auto_stats_accum.h),
// without a device: the keys sort as the doubles do and give them back exactly, and merging
// every point's statistics through them (what the kernel's atomics do, in any order) gives
// the host's gatherAutoSensorStats() to the bit.
#include "auto_stats_accum.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "fragg_map/internal/auto_sensor.h"

namespace fragg::cuda {
namespace {

uint64_t bits(double v) {
  uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

TEST(AutoStatsAccum, KeysSortAsTheDoublesAndGiveThemBack) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> v = {-inf,   -1.0,   -0.75, -1e-300, -0.0, 0.0,
                           5e-324, 1e-300, 0.5,   1.0,     7.25, inf};
  for (size_t i = 0; i < v.size(); ++i) {
    EXPECT_EQ(bits(fromOrderedKey(orderedKey(v[i]))), bits(v[i])) << v[i];
    for (size_t j = i + 1; j < v.size(); ++j)
      EXPECT_LT(orderedKey(v[i]), orderedKey(v[j])) << v[i] << " " << v[j];
  }
}

/// The kernel's merge, on the host: integer max / min / add / and over the keys.
void mergeLikeTheDevice(AutoStatsAccum* a, const AutoSensorStats& s) {
  a->max_dist_key = std::max(a->max_dist_key, orderedKey(s.max_dist_m));
  a->sin_min_key = std::min(a->sin_min_key, orderedKey(s.sin_min));
  a->sin_max_key = std::max(a->sin_max_key, orderedKey(s.sin_max));
  for (int i = 0; i < 3; ++i) a->dir_sum[i] += static_cast<unsigned long long>(s.dir_sum_fx[i]);
  a->valid += s.valid;
  for (int k = 0; k < 6; ++k) {
    if (!s.fit[k].fits) {
      a->fits[k] = 0;
      continue;
    }
    a->tan_h_key[k] = std::max(a->tan_h_key[k], orderedKey(s.fit[k].tan_h));
    a->tan_v_key[k] = std::max(a->tan_v_key[k], orderedKey(s.fit[k].tan_v));
  }
}

TEST(AutoStatsAccum, PointByPointMergeGivesTheHostsStatistics) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (int kind = 0; kind < 3; ++kind) {  // camera, all around, all around with z = -0
    PointCloud cloud;
    for (int i = 0; i < 4000; ++i) {
      const float z = 0.5f + 3.f * std::fabs(u(rng));
      if (kind == 0)
        cloud.points_S.emplace_back(u(rng) * 0.5f * z, u(rng) * 0.4f * z, z);
      else
        cloud.points_S.emplace_back(u(rng) * 9.f, u(rng) * 9.f, kind == 2 ? -0.f : u(rng));
    }
    cloud.points_S.emplace_back(std::nanf(""), 0.f, 1.f);
    cloud.points_S.emplace_back(0.f, 0.f, 0.f);
    const AutoSensorStats host = gatherAutoSensorStats(cloud);
    std::shuffle(cloud.points_S.begin(), cloud.points_S.end(), rng);
    AutoStatsAccum acc = AutoStatsAccum::empty();
    for (const Eigen::Vector3f& p : cloud.points_S) {
      AutoSensorStats one;
      addAutoSensorPoint(p.x(), p.y(), p.z(), sensorAxisTable(), one);
      mergeLikeTheDevice(&acc, one);
    }
    const AutoSensorStats dev = acc.stats();
    EXPECT_EQ(bits(dev.max_dist_m), bits(host.max_dist_m)) << kind;
    EXPECT_EQ(bits(dev.sin_min), bits(host.sin_min)) << kind;
    EXPECT_EQ(bits(dev.sin_max), bits(host.sin_max)) << kind;
    for (int i = 0; i < 3; ++i) EXPECT_EQ(dev.dir_sum_fx[i], host.dir_sum_fx[i]) << kind;
    EXPECT_EQ(dev.valid, host.valid) << kind;
    EXPECT_EQ(dev.valid, 4000u) << kind;
    for (int k = 0; k < 6; ++k) {
      EXPECT_EQ(dev.fit[k].fits, host.fit[k].fits) << kind << " " << k;
      EXPECT_EQ(bits(dev.fit[k].tan_h), bits(host.fit[k].tan_h)) << kind << " " << k;
      EXPECT_EQ(bits(dev.fit[k].tan_v), bits(host.fit[k].tan_v)) << kind << " " << k;
    }
    if (kind == 0) {
      EXPECT_TRUE(dev.fit[4].fits);
    }
  }
}

TEST(AutoStatsAccum, NoPointIsTheEmptyStatistics) {
  const AutoSensorStats s = AutoStatsAccum::empty().stats();
  const AutoSensorStats e;
  EXPECT_EQ(bits(s.max_dist_m), bits(e.max_dist_m));
  EXPECT_EQ(bits(s.sin_min), bits(e.sin_min));
  EXPECT_EQ(bits(s.sin_max), bits(e.sin_max));
  EXPECT_EQ(s.valid, 0u);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(s.fit[k].fits, 1);
}

}  // namespace
}  // namespace fragg::cuda
