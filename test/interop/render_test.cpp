// PNG rendering: image size, colours at known pixels (read back with libpng), limits.
#include "fragg_map/interop/render.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "interop_test_util.h"
#include "png_test_util.h"

namespace fragg {
namespace {

using test::fileExists;
using test::Image;
using test::listDir;
using test::paramsAt;
using test::readPng;
using test::setCell;
using test::testDir;

/// Voxel columns at 10 cm, x in [0, 2], y in [0, 1]:
///   (0,0): occupied at z = 0 and z = 5, free at z = 2  -> top z = 5
///   (2,0): occupied at z = 1, free at z = 3            -> top z = 1
///   (1,1): free at z = 0 and z = 4                      -> free only
///   (1,0): free at z = 1, in-band at z = 0              -> free only
///   (0,1), (2,1): never observed                        -> unknown
Map columnsMap() {
  Map map(paramsAt(0.1));
  const int16_t occ = map.model().max_fx, free = map.model().min_fx;
  setCell(map, {0, 0, 0}, occ);
  setCell(map, {0, 0, 5}, occ);
  setCell(map, {0, 0, 2}, free);
  setCell(map, {2, 0, 1}, occ);
  setCell(map, {2, 0, 3}, free);
  setCell(map, {1, 1, 0}, free);
  setCell(map, {1, 1, 4}, free);
  setCell(map, {1, 0, 1}, free);
  setCell(map, {1, 0, 0}, 30);
  return map;
}

/// Colour of voxel column (x, y) in an image of `scale` px per voxel whose top row is y_max.
Rgb pixelOf(const Image& img, int x, int y, int y_max, int scale) {
  return img.at(x * scale + scale / 2, (y_max - y) * scale + scale / 2);
}

TEST(Render, HeightColorRamp) {
  EXPECT_EQ(heightColor(0.0), (Rgb{0, 0, 255}));
  EXPECT_EQ(heightColor(0.5), (Rgb{0, 255, 0}));
  EXPECT_EQ(heightColor(1.0), (Rgb{255, 0, 0}));
  EXPECT_EQ(heightColor(-3.0), heightColor(0.0));
  EXPECT_EQ(heightColor(7.0), heightColor(1.0));
}

TEST(Render, TopDownColoursColumnsByTheirHighestOccupiedCell) {
  const std::string path = testDir() + "/top.png";
  RenderOptions options;
  options.scale = 3;
  const RenderInfo info = renderTopDown(columnsMap(), path, options);
  EXPECT_EQ(info.width_px, 9);
  EXPECT_EQ(info.height_px, 6);
  EXPECT_EQ(info.voxels_per_pixel, 1);
  EXPECT_EQ(info.occupied_columns, 2u);
  EXPECT_NEAR(info.z_min_m, 0.15, 1e-9);
  EXPECT_NEAR(info.z_max_m, 0.55, 1e-9);

  const Image img = readPng(path);
  ASSERT_EQ(img.width, 9);
  ASSERT_EQ(img.height, 6);
  EXPECT_EQ(pixelOf(img, 0, 0, 1, 3), heightColor(1.0));  // top z = 5, the highest
  EXPECT_EQ(pixelOf(img, 2, 0, 1, 3), heightColor(0.0));  // top z = 1, the lowest
  EXPECT_EQ(pixelOf(img, 1, 1, 1, 3), options.free_color);
  EXPECT_EQ(pixelOf(img, 1, 0, 1, 3), options.free_color);
  EXPECT_EQ(pixelOf(img, 0, 1, 1, 3), options.unknown_color);
  EXPECT_EQ(pixelOf(img, 2, 1, 1, 3), options.unknown_color);
  // Every pixel of a voxel's 3 x 3 square has its colour: x = 0..2, y = 3..5 is voxel (0, 0).
  for (int py = 3; py < 6; ++py)
    for (int px = 0; px < 3; ++px) EXPECT_EQ(img.at(px, py), heightColor(1.0));
}

TEST(Render, SliceShowsTheStateOfEachCellInTheLayer) {
  const std::string dir = testDir();
  const Map map = columnsMap();
  RenderOptions options;
  options.scale = 2;
  // z = 0.05 m is voxel layer 0: (0,0) occupied, (1,1) free, (1,0) in the band (unknown).
  RenderInfo info = renderSlice(map, 0.05, dir + "/z0.png", options);
  EXPECT_EQ(info.width_px, 6);
  EXPECT_EQ(info.height_px, 4);
  EXPECT_EQ(info.occupied_columns, 1u);
  Image img = readPng(dir + "/z0.png");
  ASSERT_EQ(img.width, 6);
  ASSERT_EQ(img.height, 4);
  EXPECT_EQ(pixelOf(img, 0, 0, 1, 2), options.occupied_color);
  EXPECT_EQ(pixelOf(img, 1, 1, 1, 2), options.free_color);
  EXPECT_EQ(pixelOf(img, 1, 0, 1, 2), options.unknown_color);
  EXPECT_EQ(pixelOf(img, 2, 0, 1, 2), options.unknown_color);

  // z = 0.12 m is layer 1: (2,0) occupied, (1,0) free, (0,0) unknown.
  renderSlice(map, 0.12, dir + "/z1.png", options);
  img = readPng(dir + "/z1.png");
  EXPECT_EQ(pixelOf(img, 2, 0, 1, 2), options.occupied_color);
  EXPECT_EQ(pixelOf(img, 1, 0, 1, 2), options.free_color);
  EXPECT_EQ(pixelOf(img, 0, 0, 1, 2), options.unknown_color);
  EXPECT_NE(options.occupied_color, options.free_color);
  EXPECT_NE(options.occupied_color, options.unknown_color);
  EXPECT_NE(options.free_color, options.unknown_color);
}

TEST(Render, CropBoxSetsTheImageExtentAndFiltersHeights) {
  const std::string path = testDir() + "/crop.png";
  RenderOptions options;
  // x voxels -1..2, y voxels 0..0, heights up to z voxel 2 (so (0,0) tops out at z = 0).
  options.crop =
      Eigen::AlignedBox3d(Eigen::Vector3d(-0.05, 0.01, -1.0), Eigen::Vector3d(0.25, 0.09, 0.29));
  const RenderInfo info = renderTopDown(columnsMap(), path, options);
  EXPECT_EQ(info.width_px, 4);
  EXPECT_EQ(info.height_px, 1);
  const Image img = readPng(path);
  ASSERT_EQ(img.width, 4);
  EXPECT_EQ(img.at(0, 0), options.unknown_color);  // x = -1: outside the map
  EXPECT_EQ(img.at(1, 0), heightColor(0.0));       // (0,0): top z = 0 (z = 5 cropped)
  EXPECT_EQ(img.at(2, 0), options.free_color);     // (1,0)
  EXPECT_EQ(img.at(3, 0), heightColor(1.0));       // (2,0): top z = 1
}

TEST(Render, LargeMapsAreDownscaledOrRefused) {
  const std::string dir = testDir();
  Map map(paramsAt(0.1));
  for (int x = 0; x < 10; ++x) setCell(map, {x, 0, 0}, map.model().min_fx);
  setCell(map, {9, 0, 0}, map.model().max_fx);
  RenderOptions options;
  options.max_side_px = 4;
  const RenderInfo info = renderTopDown(map, dir + "/small.png", options);
  EXPECT_EQ(info.voxels_per_pixel, 3);
  EXPECT_EQ(info.width_px, 4);  // ceil(10 / 3)
  EXPECT_EQ(info.height_px, 1);
  const Image img = readPng(dir + "/small.png");
  ASSERT_EQ(img.width, 4);
  EXPECT_EQ(img.at(0, 0), options.free_color);
  EXPECT_EQ(img.at(3, 0), heightColor(0.5));  // voxel 9: the only (so middle) height

  // A smaller scale first: 3 px per voxel would be 30 px, 2 px fit in 20.
  options.max_side_px = 20;
  options.scale = 3;
  const RenderInfo rescaled = renderSlice(map, 0.0, dir + "/rescaled.png", options);
  EXPECT_EQ(rescaled.scale, 2);
  EXPECT_EQ(rescaled.voxels_per_pixel, 1);
  EXPECT_EQ(rescaled.width_px, 20);
  EXPECT_EQ(readPng(dir + "/rescaled.png").width, 20);

  options.auto_downscale = false;
  EXPECT_THROW(renderSlice(map, 0.0, dir + "/refused.png", options), InvalidArgument);
  options.max_side_px = 4;
  options.scale = 1;
  EXPECT_THROW(renderTopDown(map, dir + "/refused.png", options), InvalidArgument);
  EXPECT_FALSE(test::fileExists(dir + "/refused.png"));
}

TEST(Render, BadInputIsRejectedWithoutAFile) {
  const std::string dir = testDir();
  EXPECT_THROW(renderTopDown(Map(paramsAt(0.1)), dir + "/empty.png"), InvalidArgument);
  RenderOptions options;
  options.scale = 0;
  EXPECT_THROW(renderTopDown(columnsMap(), dir + "/scale.png", options), InvalidArgument);
  options.scale = 1;
  options.crop = Eigen::AlignedBox3d(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(0, 0, 0));
  EXPECT_THROW(renderTopDown(columnsMap(), dir + "/crop.png", options), InvalidArgument);
  EXPECT_THROW(renderSlice(columnsMap(), std::nan(""), dir + "/nan.png"), InvalidArgument);
  EXPECT_TRUE(listDir(dir).empty());
  EXPECT_THROW(renderTopDown(columnsMap(), dir + "/missing/dir/x.png"), IoError);
  EXPECT_TRUE(listDir(dir).empty());
}

}  // namespace
}  // namespace fragg
