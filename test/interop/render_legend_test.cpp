// The legend below a rendered map (appendLegend, RenderOptions::legend) and the font it is
// written in (src/interop/glyphs.h): glyph pixels where the font says, the map's pixels
// unchanged above the strip, each colour of the view in the strip, read back from the PNG.
#include <gtest/gtest.h>

#include <bitset>
#include <set>
#include <string>
#include <tuple>

#include "fragg_map/interop/render.h"
#include "glyphs.h"
#include "interop_test_util.h"
#include "png_test_util.h"

namespace fragg {
namespace {

using test::Image;
using test::paramsAt;
using test::readPng;
using test::setCell;
using test::testDir;

RenderImage blank(int w, int h) {
  RenderImage image;
  image.info.width_px = w;
  image.info.height_px = h;
  image.rgb.assign(static_cast<size_t>(w) * h * 3, 255);
  return image;
}

bool inked(const RenderImage& image, int x, int y) {
  return image.rgb[(static_cast<size_t>(y) * image.info.width_px + x) * 3] == 0;
}

TEST(Glyphs, TextIsDrawnWhereTheFontSaysAtAnyScale) {
  // 'A': " ### ", "#   #", "#   #", "#####", "#   #", "#   #", "#   #" (18 pixels).
  const auto rows = internal::glyphRows('A');
  int bits = 0;
  for (uint8_t r : rows) bits += static_cast<int>(std::bitset<8>(r).count());
  ASSERT_EQ(bits, 18);
  for (int scale : {1, 3}) {
    RenderImage image = blank(20, 30);
    internal::drawText(image, 2, 1, "A", Rgb{0, 0, 0}, scale);
    int ink = 0;
    for (int y = 0; y < 30; ++y)
      for (int x = 0; x < 20; ++x) ink += inked(image, x, y);
    EXPECT_EQ(ink, 18 * scale * scale);
    EXPECT_FALSE(inked(image, 2, 1));                          // the top row's left corner
    EXPECT_TRUE(inked(image, 2 + scale, 1));                   // the top row's bar
    EXPECT_TRUE(inked(image, 2, 1 + 3 * scale));               // the cross bar, left end
    EXPECT_TRUE(inked(image, 2 + 4 * scale, 1 + 6 * scale));   // the right leg's foot
    EXPECT_FALSE(inked(image, 2 + 2 * scale, 1 + 6 * scale));  // between the legs
  }
  EXPECT_EQ(internal::glyphRows('a'), internal::glyphRows('A'));
  EXPECT_EQ(internal::glyphRows('~'), internal::glyphRows('?'));
  EXPECT_NE(internal::glyphRows('0'), internal::glyphRows('O'));
  EXPECT_EQ(internal::textWidthPx("", 2), 0);
  EXPECT_EQ(internal::textWidthPx("AB", 2), (6 + 5) * 2);
  // Clipped at the image's edges, never written outside it.
  RenderImage small = blank(3, 3);
  internal::drawText(small, -2, -2, "WW", Rgb{0, 0, 0}, 2);
  EXPECT_EQ(small.rgb.size(), 27u);
}

/// A 3 x 2 m floor of free cells at 10 cm with two occupied columns at z 0.05 and 0.45 m.
Map floorMap() {
  Map map(paramsAt(0.1));
  for (int x = 0; x < 30; ++x)
    for (int y = 0; y < 20; ++y) setCell(map, {x, y, 0}, map.model().min_fx);
  setCell(map, {5, 5, 0}, map.model().max_fx);
  setCell(map, {20, 10, 4}, map.model().max_fx);
  return map;
}

std::set<std::tuple<int, int, int>> coloursIn(const Image& img, int y0, int y1) {
  std::set<std::tuple<int, int, int>> colours;
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Rgb c = img.at(x, y);
      colours.insert({c.r, c.g, c.b});
    }
  return colours;
}

bool has(const std::set<std::tuple<int, int, int>>& colours, const Rgb& c) {
  return colours.count({c.r, c.g, c.b}) > 0;
}

TEST(RenderLegend, TopViewLegendBelowTheUnchangedMap) {
  const std::string dir = testDir();
  const Map map = floorMap();
  RenderOptions options;
  const RenderInfo plain = renderTopDown(map, dir + "/plain.png", options);
  options.legend = true;
  const RenderInfo info = renderTopDown(map, dir + "/legend.png", options);
  EXPECT_EQ(info.map_width_px, plain.width_px);
  EXPECT_EQ(info.map_height_px, plain.height_px);
  EXPECT_GT(info.legend_height_px, 0);
  EXPECT_EQ(info.height_px, plain.height_px + info.legend_height_px);
  EXPECT_GT(info.width_px, plain.width_px) << "the legend's lines are wider than 30 px";

  const Image a = readPng(dir + "/plain.png"), b = readPng(dir + "/legend.png");
  ASSERT_EQ(b.width, info.width_px);
  ASSERT_EQ(b.height, info.height_px);
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) ASSERT_EQ(b.at(x, y), a.at(x, y)) << x << " " << y;
    for (int x = a.width; x < b.width; ++x) ASSERT_EQ(b.at(x, y), (Rgb{255, 255, 255}));
  }
  const auto strip = coloursIn(b, a.height, b.height);
  EXPECT_TRUE(has(strip, Rgb{0, 0, 0})) << "no text";
  EXPECT_TRUE(has(strip, heightColor(0.0))) << "the ramp's low end";
  EXPECT_TRUE(has(strip, heightColor(1.0))) << "the ramp's high end";
  EXPECT_TRUE(has(strip, options.free_color));
  EXPECT_TRUE(has(strip, options.unknown_color));
  EXPECT_FALSE(has(strip, options.occupied_color)) << "the top view colours by height";
}

TEST(RenderLegend, SliceLegendShowsTheThreeStates) {
  const std::string dir = testDir();
  RenderOptions options;
  options.legend = true;
  options.scale = 20;  // 600 px wide: text at 1 image px a glyph px (one more per 400 px)
  const RenderInfo info = renderSlice(floorMap(), 0.05, dir + "/slice.png", options);
  EXPECT_EQ(info.map_width_px, 600);
  EXPECT_EQ(info.width_px, 600) << "the legend fits under a 600 px map";
  const Image img = readPng(dir + "/slice.png");
  ASSERT_EQ(img.height, info.map_height_px + info.legend_height_px);
  const auto strip = coloursIn(img, info.map_height_px, img.height);
  EXPECT_TRUE(has(strip, Rgb{0, 0, 0}));
  EXPECT_TRUE(has(strip, options.occupied_color));
  EXPECT_TRUE(has(strip, options.free_color));
  EXPECT_TRUE(has(strip, options.unknown_color));
  EXPECT_FALSE(has(strip, heightColor(0.0))) << "no height ramp in a slice's legend";
  // The same slice without a legend is the map part of this one.
  options.legend = false;
  renderSlice(floorMap(), 0.05, dir + "/bare.png", options);
  const Image bare = readPng(dir + "/bare.png");
  ASSERT_EQ(bare.height, info.map_height_px);
  for (int y = 0; y < bare.height; y += 7)
    for (int x = 0; x < bare.width; x += 7) ASSERT_EQ(img.at(x, y), bare.at(x, y));
}

}  // namespace
}  // namespace fragg
