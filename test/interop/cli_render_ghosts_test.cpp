// `fragg_map render --highlight-ghosts STATIC.obj`, run as a user would, on a hand-written map:
// the columns of occupied cells far from the static scene (ghosts, as `fragg_map eval` counts
// them) are pure red, the columns of occupied cells on or inside the scene's box are the plain
// render faded, the printed count is the ghost count; bad combinations exit 2.
#include <gtest/gtest.h>

#include <string>

#include "fragg_map/map.h"
#include "interop_test_util.h"
#include "png_test_util.h"

namespace fragg {
namespace {

using test::runCli;
using test::testDir;
using test::writeBytes;

// A closed box 0..1 x 0..1 x 0..0.5 m: the static truth.
const char kBoxObj[] =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 0.5\nv 1 0 0.5\nv 1 1 0.5\nv 0 1 0.5\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\n"
    "f 3 8 7\nf 4 1 5\nf 4 5 8\n";

// 0.1 m cells, keys y 0..9: occupied through the box (x 0..9, z 0..4: on or inside it), free
// x 10..19, occupied again at x 20..24, z 0..2 (2 m from the box: ghosts).
std::string ghostMap(const std::string& dir) {
  MapParams params;
  params.resolution_m = 0.1;
  Map map(params);
  map.writeCells([](CellWriter& w) {
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 25; ++x)
        for (int z = 0; z < 5; ++z) {
          if (x < 10)
            w.set({x, y, z}, Cell{1, 3000});
          else if (x < 20)
            w.set({x, y, z}, Cell{0, -2000});
          else if (z < 3)
            w.set({x, y, z}, Cell{1, 3000});
        }
  });
  const std::string path = dir + "/ghosts.fgm";
  map.save(path);
  return path;
}

TEST(CliRenderGhosts, GhostColumnsRedTheRestFaded) {
  const std::string dir = testDir();
  const std::string path = ghostMap(dir);
  writeBytes(dir + "/box.obj", kBoxObj);
  const int scale = 4;
  auto r = runCli(dir, "render '" + path + "' -o '" + dir + "/plain.png' --scale 4 --no-legend");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runCli(dir, "render '" + path + "' -o '" + dir + "/ghosts.png' --scale 4 --no-legend " +
                      "--highlight-ghosts '" + dir + "/box.obj'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ghosts: 150 cells"), std::string::npos) << r.out;  // 5 x 10 x 3

  const test::Image plain = test::readPng(dir + "/plain.png");
  const test::Image drawn = test::readPng(dir + "/ghosts.png");
  ASSERT_EQ(plain.width, 25 * scale);
  ASSERT_EQ(plain.height, 10 * scale);
  ASSERT_EQ(drawn.width, plain.width);
  ASSERT_EQ(drawn.height, plain.height);
  int red = 0, faded_ok = 0;
  for (int py = 0; py < plain.height; ++py)
    for (int px = 0; px < plain.width; ++px) {
      const Rgb a = plain.at(px, py), b = drawn.at(px, py);
      if (px / scale >= 20) {
        EXPECT_EQ(b, (Rgb{255, 0, 0})) << "ghost column " << px / scale;
        red += b == Rgb{255, 0, 0};
      } else {
        const Rgb faded{static_cast<uint8_t>((a.r + 128) / 2),
                        static_cast<uint8_t>((a.g + 128) / 2),
                        static_cast<uint8_t>((a.b + 128) / 2)};
        EXPECT_EQ(b, faded) << "column " << px / scale << " holds no ghost";
        faded_ok += b == faded;
      }
    }
  EXPECT_EQ(red, 5 * scale * 10 * scale);
  EXPECT_EQ(faded_ok, 20 * scale * 10 * scale);
}

TEST(CliRenderGhosts, BadArgumentsExitTwo) {
  const std::string dir = testDir();
  const std::string path = ghostMap(dir);
  writeBytes(dir + "/box.obj", kBoxObj);
  const std::string base = "render '" + path + "' -o '" + dir + "/x.png' ";
  for (const std::string args : {"--highlight-ghosts '" + dir + "/box.obj' --view slice --z 0.1",
                                 "--highlight-ghosts '" + dir + "/box.obj' --frontiers",
                                 "--highlight-ghosts '" + dir + "/box.stl'"}) {
    const auto r = runCli(dir, base + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find("--highlight-ghosts"), std::string::npos) << args << ": " << r.err;
  }
  const auto r = runCli(dir, base + "--highlight-ghosts '" + dir + "/missing.obj'");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("missing.obj"), std::string::npos) << r.err;
  EXPECT_FALSE(test::fileExists(dir + "/x.png"));
}

}  // namespace
}  // namespace fragg
