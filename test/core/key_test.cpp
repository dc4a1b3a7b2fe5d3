#include "fragg_map/key.h"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"

namespace fragg {
namespace {

TEST(KeyTest, NegativeVoxelsFloorToTheirBlock) {
  EXPECT_EQ(blockKeyOf(VoxelKey{-1, -8, -9}), (BlockKey{-1, -1, -2}));
  EXPECT_EQ(blockKeyOf(VoxelKey{0, 7, 8}), (BlockKey{0, 0, 1}));
  EXPECT_EQ(cellIndexOf(VoxelKey{-1, 0, 0}), 7);
  EXPECT_EQ(cellIndexOf(VoxelKey{0, -1, 0}), 7 * 8);
  EXPECT_EQ(cellIndexOf(VoxelKey{0, 0, -1}), 7 * 64);
}

TEST(KeyTest, VoxelKeyOfBlockAndCellRoundTrips) {
  for (int32_t x : {-2147483647 - 1, -9, -8, -1, 0, 7, 8, 2147483647})
    for (int32_t y : {-17, 3})
      for (int32_t z : {-1, 1000000}) {
        const VoxelKey v{x, y, z};
        EXPECT_EQ(voxelKeyOf(blockKeyOf(v), cellIndexOf(v)), v);
      }
}

TEST(KeyTest, MapKeysFloorNegativeAndFarCoordinates) {
  MapParams p;
  p.resolution_m = 0.05;
  Map map(p);
  EXPECT_EQ(map.keyOf({-0.001, 0.0, 0.049}), (VoxelKey{-1, 0, 0}));
  EXPECT_EQ(map.keyOf({-0.05, -0.0500001, 0.05}), (VoxelKey{-1, -2, 1}));
  // 100,000 km at 5 cm is beyond 16-bit keys but inside int32.
  const VoxelKey far = map.keyOf({1.0e8, -1.0e8, 0.0});
  EXPECT_EQ(far.x, 2000000000);
  EXPECT_EQ(far.y, -2000000000);
  const Eigen::Vector3d c = map.centerOf(far);
  EXPECT_NEAR(c.x(), 1.0e8 + 0.025, 1e-6);
  EXPECT_THROW(map.keyOf({2.0e8, 0, 0}), InvalidArgument);
  EXPECT_THROW(map.keyOf({std::nan(""), 0, 0}), InvalidArgument);
}

TEST(KeyTest, HashSpreadsNeighbours) {
  BlockKeyHash h;
  EXPECT_NE(h({0, 0, 0}), h({1, 0, 0}));
  EXPECT_NE(h({0, 0, 1}), h({0, 1, 0}));
  EXPECT_NE(h({-1, 0, 0}), h({1, 0, 0}));
}

}  // namespace
}  // namespace fragg
