// The regions a scan's rays pass through (regionsReached: what the CUDA path pages in before
// its ray pass), against a brute-force segment / box test of every region of the box.
#include "fragg_map/internal/region_reach.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <tuple>
#include <vector>

namespace fragg::test {
namespace {

using KeySet = std::set<std::tuple<int32_t, int32_t, int32_t>>;

KeySet setOf(const std::vector<BlockKey>& keys) {
  KeySet s;
  for (const BlockKey& k : keys) s.emplace(k.x, k.y, k.z);
  return s;
}

/// Whether the segment a -> b meets the box [lo, hi] (slab test).
bool segmentMeetsBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi) {
  double t0 = 0.0, t1 = 1.0;
  const Eigen::Vector3d d = b - a;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (a[k] < lo[k] || a[k] > hi[k]) return false;
      continue;
    }
    double ta = (lo[k] - a[k]) / d[k], tb = (hi[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

/// Every region of [lo, hi] that a segment meets, the region box grown by `margin_m` (> 0: a
/// superset of the exact answer; < 0: a subset).
KeySet bruteForce(const std::vector<Eigen::Vector3d>& ends_map, const Eigen::Vector3d& origin_map,
                  double region_m, const BlockKey& lo, const BlockKey& hi, double margin_m) {
  KeySet s;
  for (int32_t z = lo.z; z <= hi.z; ++z)
    for (int32_t y = lo.y; y <= hi.y; ++y)
      for (int32_t x = lo.x; x <= hi.x; ++x) {
        const Eigen::Vector3d box_lo = Eigen::Vector3d(x, y, z) * region_m;
        const Eigen::Vector3d m = Eigen::Vector3d::Constant(margin_m);
        for (const Eigen::Vector3d& e : ends_map)
          if (segmentMeetsBox(origin_map, e, box_lo - m,
                              box_lo + Eigen::Vector3d::Constant(region_m) + m)) {
            s.emplace(x, y, z);
            break;
          }
      }
  return s;
}

Eigen::Isometry3d pose() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 0.3, 1.0).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(3.3, -1.9, 0.6);
  return T;
}

TEST(RegionReach, EqualsBruteForceSegmentBoxTest) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-9.0f, 9.0f);
  PointCloud cloud;
  for (int i = 0; i < 300; ++i) cloud.points_S.emplace_back(u(rng), u(rng), 0.3f * u(rng));
  cloud.points_S.emplace_back(std::numeric_limits<float>::quiet_NaN(), 1.0f, 1.0f);  // no return
  const Eigen::Isometry3d T = pose();
  const double region_m = 1.6;
  const BlockKey lo{-8, -9, -4}, hi{8, 6, 4};  // clips some segments
  const KeySet got = setOf(regionsReached(cloud, T, 0.0, region_m, lo, hi, 2));
  std::vector<Eigen::Vector3d> ends;
  for (const Eigen::Vector3f& p : cloud.points_S)
    if (p.allFinite()) ends.push_back(T * p.cast<double>());
  const KeySet outer = bruteForce(ends, T.translation(), region_m, lo, hi, 1e-7);
  const KeySet inner = bruteForce(ends, T.translation(), region_m, lo, hi, -1e-7);
  EXPECT_GT(inner.size(), 50u);
  // Exact up to segments that graze a region's edge within 1e-7 m.
  EXPECT_TRUE(std::includes(outer.begin(), outer.end(), got.begin(), got.end()));
  EXPECT_TRUE(std::includes(got.begin(), got.end(), inner.begin(), inner.end()));
  // The same with one thread (and sorted by z, y, x, no duplicates).
  const std::vector<BlockKey> one = regionsReached(cloud, T, 0.0, region_m, lo, hi, 1);
  EXPECT_EQ(setOf(one), got);
  EXPECT_EQ(one.size(), got.size());
  EXPECT_TRUE(std::is_sorted(one.begin(), one.end(), [](const BlockKey& a, const BlockKey& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  }));
}

TEST(RegionReach, ASampleOfTheRaysWalksEveryKthPoint) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-9.0f, 9.0f);
  PointCloud cloud, sample;
  for (int i = 0; i < 1000; ++i) cloud.points_S.emplace_back(u(rng), u(rng), 0.3f * u(rng));
  for (size_t i = 0; i < cloud.points_S.size(); i += 4)
    sample.points_S.push_back(cloud.points_S[i]);
  const Eigen::Isometry3d T = pose();
  const BlockKey lo{-8, -9, -4}, hi{8, 6, 4};
  // 1000 points, at most 250 rays: every 4th point.
  const KeySet sampled = setOf(regionsReached(cloud, T, 0.0, 1.6, lo, hi, 2, 250));
  EXPECT_EQ(sampled, setOf(regionsReached(sample, T, 0.0, 1.6, lo, hi, 2)));
  const KeySet all = setOf(regionsReached(cloud, T, 0.0, 1.6, lo, hi, 2));
  EXPECT_LT(sampled.size(), all.size());  // a sample: some regions only the others reach
  EXPECT_TRUE(std::includes(all.begin(), all.end(), sampled.begin(), sampled.end()));
  // A limit above the point count walks every ray.
  EXPECT_EQ(setOf(regionsReached(cloud, T, 0.0, 1.6, lo, hi, 2, 5000)), all);
}

TEST(RegionReach, PointsBeyondMaxRangeEndThere) {
  PointCloud cloud;
  cloud.points_S.emplace_back(20.0f, 0.1f, 0.1f);  // along +x, beyond a 5 m range
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const KeySet got = setOf(regionsReached(cloud, T, 5.0, 1.0, {-2, -2, -2}, {30, 2, 2}, 1));
  KeySet want;
  for (int32_t x = 0; x <= 4; ++x) want.emplace(x, 0, 0);  // ends at x = 4.9999 m
  EXPECT_EQ(got, want);
  // Without a range the ray runs to its point (and is clipped by the box's x <= 30).
  EXPECT_EQ(setOf(regionsReached(cloud, T, 0.0, 1.0, {-2, -2, -2}, {30, 2, 2}, 1)).size(), 21u);
}

TEST(RegionReach, BoxTooLargeOrEmptyGivesNothing) {
  PointCloud cloud;
  cloud.points_S.emplace_back(2.5f, 0.5f, 0.5f);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  EXPECT_TRUE(regionsReached(cloud, T, 0.0, 1.0, {0, 0, 0}, {99, 99, 99}, 1, 0, 1000).empty());
  EXPECT_TRUE(regionsReached(cloud, T, 0.0, 1.0, {3, 0, 0}, {2, 9, 9}, 1).empty());
  EXPECT_EQ(regionsReached(cloud, T, 0.0, 1.0, {0, 0, 0}, {9, 9, 9}, 1).size(), 3u);
}

}  // namespace
}  // namespace fragg::test
