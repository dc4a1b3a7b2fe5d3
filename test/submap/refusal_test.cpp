// Bad sub-map arguments are refused with InvalidArgument and leave the map untouched: its
// revision and every cell.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include "fragg_map/errors.h"
#include "submap_scenes.h"

namespace fragg {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

void expectRefused(Map& map, const Map& copy, const std::function<void(Map&)>& edit,
                   const char* label) {
  const uint64_t rev = map.revision();
  EXPECT_THROW(edit(map), InvalidArgument) << label;
  EXPECT_EQ(map.revision(), rev) << label;
  std::string why;
  EXPECT_TRUE(test::sameCells(map, copy, &why)) << label << ": " << why;
}

TEST(SubmapRefusalTest, BadBoxesAndRadii) {
  Map map = test::roomMap();
  const Map copy = test::roomMap();
  const Eigen::Vector3d lo(-1, -1, -1), hi(1, 1, 1);
  expectRefused(
      map, copy, [&](Map& m) { m.truncate(hi, lo); }, "inverted box");
  expectRefused(
      map, copy, [&](Map& m) { m.truncate(Eigen::Vector3d(kNaN, 0, 0), hi); }, "NaN");
  expectRefused(
      map, copy, [&](Map& m) { m.truncate(lo, Eigen::Vector3d(0, kInf, 0)); }, "Inf");
  expectRefused(
      map, copy, [&](Map& m) { m.extract(hi, lo); }, "extract inverted");
  expectRefused(
      map, copy, [&](Map& m) { m.truncateOutside(lo, -0.5); }, "negative radius");
  expectRefused(
      map, copy, [&](Map& m) { m.truncateOutside(lo, kNaN); }, "NaN radius");
  expectRefused(
      map, copy, [&](Map& m) { m.truncateOutside(lo, kInf); }, "Inf radius");
  expectRefused(
      map, copy, [&](Map& m) { m.truncateOutside(Eigen::Vector3d(kNaN, 0, 0), 1.0); },
      "NaN centre");
}

TEST(SubmapRefusalTest, IncompatibleSubMapsAndBadPoses) {
  Map map = test::roomMap();
  const Map copy = test::roomMap();
  const Map sub = test::roomMap();  // compatible, so only the pose is wrong below
  expectRefused(
      map, copy, [&](Map& m) { m.merge(test::roomMap(test::cpuParams(0.1)), MergeMode::kAdd); },
      "resolution");
  for (int field = 0; field < 4; ++field) {
    MapParams p = test::cpuParams();
    double* v[] = {&p.occupancy.prob_hit, &p.occupancy.prob_miss, &p.occupancy.clamp_min,
                   &p.occupancy.clamp_max};
    *v[field] += 0.01;
    Map other(p);
    other.writeCells([](CellWriter& w) { w.set({0, 0, 0}, Cell{1, 100}); });
    expectRefused(
        map, copy, [&](Map& m) { m.merge(other, MergeMode::kOverwrite); }, "occupancy model");
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().x() = kNaN;
  expectRefused(
      map, copy, [&](Map& m) { m.merge(sub, MergeMode::kAdd, T); }, "NaN pose");
  T = Eigen::Isometry3d::Identity();
  T.linear()(0, 0) = kInf;
  expectRefused(
      map, copy, [&](Map& m) { m.merge(sub, MergeMode::kAdd, T); }, "Inf pose");
  T = Eigen::Isometry3d::Identity();
  T.linear() *= 1.01;
  expectRefused(
      map, copy, [&](Map& m) { m.merge(sub, MergeMode::kAdd, T); }, "scaled pose");
  T = Eigen::Isometry3d::Identity();
  T.linear()(2, 2) = -1.0;
  expectRefused(
      map, copy, [&](Map& m) { m.merge(sub, MergeMode::kAdd, T); }, "reflection");
  T = Eigen::Isometry3d::Identity();
  T.translation().x() = 2e9;
  expectRefused(
      map, copy, [&](Map& m) { m.merge(sub, MergeMode::kAdd, T); }, "beyond keys");
  expectRefused(
      map, copy, [&](Map& m) { m.merge(m, MergeMode::kAdd); }, "itself");
  EXPECT_THROW(mergeModeFromString("sum"), InvalidArgument);
}

}  // namespace
}  // namespace fragg
