// Occupied voxel centres and their PLY / PCD files.
#include "fragg_map/interop/export.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "interop_test_util.h"

namespace fragg {
namespace {

using test::listDir;
using test::paramsAt;
using test::readBytes;
using test::setCell;
using test::testDir;

/// Occupied, free, in-band and unobserved cells at 10 cm; the occupied ones are listed in the
/// order occupiedCenters() must return them (z, then y, then x).
Map sampleMap(std::vector<VoxelKey>* occupied) {
  Map map(paramsAt(0.1));
  const int16_t occ = map.model().max_fx, free = map.model().min_fx;
  *occupied = {{-3, -1, -2}, {5, -1, -2}, {0, 0, 0}, {1, 0, 0}, {-20, 7, 0}, {2, 2, 9}};
  for (const VoxelKey& k : *occupied) setCell(map, k, occ);
  setCell(map, {4, 0, 0}, free);
  setCell(map, {0, 1, 0}, 50);  // p ~ 0.512: inside the unknown band
  setCell(map, {0, 2, 0}, -50);
  setCell(map, {9, 9, 9}, free);
  return map;
}

std::vector<Eigen::Vector3f> centersOf(const Map& map, const std::vector<VoxelKey>& keys) {
  std::vector<Eigen::Vector3f> out;
  for (const VoxelKey& k : keys) out.push_back(map.centerOf(k).cast<float>());
  return out;
}

TEST(Export, OccupiedCentersAreTheOccupiedCellsSortedByKey) {
  std::vector<VoxelKey> occupied;
  const Map map = sampleMap(&occupied);
  const std::vector<Eigen::Vector3f> centers = occupiedCenters(map);
  const std::vector<Eigen::Vector3f> expected = centersOf(map, occupied);
  ASSERT_EQ(centers.size(), expected.size());
  for (size_t i = 0; i < centers.size(); ++i) {
    EXPECT_TRUE(centers[i].isApprox(expected[i], 1e-6f))
        << i << ": " << centers[i].transpose() << " vs " << expected[i].transpose();
  }
  EXPECT_TRUE(centers[2].isApprox(Eigen::Vector3f(0.05f, 0.05f, 0.05f)));
}

TEST(Export, PlyHoldsTheOccupiedCenters) {
  std::vector<VoxelKey> occupied;
  const Map map = sampleMap(&occupied);
  const std::string path = testDir() + "/occupied.ply";
  EXPECT_EQ(exportOccupiedPly(map, path), occupied.size());
  const std::string bytes = readBytes(path);
  EXPECT_EQ(bytes.rfind("ply\n", 0), 0u);
  EXPECT_NE(bytes.find("element vertex 6\n"), std::string::npos);
  const PointCloud cloud = readPly(path);
  const std::vector<Eigen::Vector3f> expected = centersOf(map, occupied);
  ASSERT_EQ(cloud.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(cloud.points_S[i], expected[i]);
}

TEST(Export, PcdHoldsTheOccupiedCenters) {
  std::vector<VoxelKey> occupied;
  const Map map = sampleMap(&occupied);
  const std::string path = testDir() + "/occupied.pcd";
  EXPECT_EQ(exportOccupiedPcd(map, path), occupied.size());
  const std::string bytes = readBytes(path);
  EXPECT_NE(bytes.find("POINTS 6\n"), std::string::npos);
  EXPECT_NE(bytes.find("FIELDS x y z"), std::string::npos);
  const PointCloud cloud = readPcd(path);
  const std::vector<Eigen::Vector3f> expected = centersOf(map, occupied);
  ASSERT_EQ(cloud.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(cloud.points_S[i], expected[i]);
}

TEST(Export, MapWithoutOccupiedCellsGivesAnEmptyFile) {
  Map map(paramsAt(0.05));
  setCell(map, {1, 2, 3}, map.model().min_fx);
  const std::string dir = testDir();
  EXPECT_EQ(exportOccupiedPly(map, dir + "/none.ply"), 0u);
  EXPECT_EQ(exportOccupiedPcd(map, dir + "/none.pcd"), 0u);
  EXPECT_EQ(readPly(dir + "/none.ply").size(), 0u);
  EXPECT_EQ(readPcd(dir + "/none.pcd").size(), 0u);
}

TEST(Export, UnwritableTargetThrowsAndLeavesNothing) {
  std::vector<VoxelKey> occupied;
  const Map map = sampleMap(&occupied);
  const std::string dir = testDir();
  EXPECT_THROW(exportOccupiedPly(map, dir + "/no/such/dir/x.ply"), IoError);
  EXPECT_THROW(exportOccupiedPcd(map, dir + "/no/such/dir/x.pcd"), IoError);
  EXPECT_TRUE(listDir(dir).empty());
}

}  // namespace
}  // namespace fragg
