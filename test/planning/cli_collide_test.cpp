// `fragg_map collide` run as a user would: per-waypoint answers and path mode as JSON, every
// shape, and bad input refused with one line and the CLI's exit codes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/map.h"
#include "geometry/mesh_test_util.h"
#include "interop_test_util.h"
#include "png_test_util.h"

namespace fragg {
namespace {

using test::runCli;
using test::testDir;

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

/// A wall of occupied cells at x in [1.0, 1.1] (0.1 m cells), y and z in [-0.5, 0.6].
std::string wallMap(const std::string& dir) {
  MapParams params;
  params.resolution_m = 0.1;
  Map map(params);
  map.writeCells([](CellWriter& w) {
    for (int z = -5; z <= 5; ++z)
      for (int y = -5; y <= 5; ++y) w.set({10, y, z}, Cell{1, 3000});
  });
  const std::string path = dir + "/wall.fgm";
  map.save(path);
  return path;
}

TEST(CliCollide, WaypointsAndPathAsJson) {
  const std::string dir = testDir();
  const std::string map = wallMap(dir), wp = dir + "/wp.txt";
  writeText(wp,
            "# x y z qx qy qz qw\n0.5 0.05 0.05 0 0 0 1\n1.6 0.05 0.05 0 0 0 1\n"
            "1.05 0.05 0.05 0 0 0 1\n");
  auto r = runCli(dir, "collide '" + map + "' --waypoints '" + wp + "' --sphere 0.04 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["waypoints"], 3);
  EXPECT_EQ(j["collides"], nlohmann::json({false, false, true}));
  EXPECT_EQ(j["colliding"], 1);
  EXPECT_EQ(j["first_collision"], 2);
  EXPECT_GE(j["ms"].get<double>(), 0.0);

  r = runCli(dir,
             "collide '" + map + "' --waypoints '" + wp + "' --box 0.08 0.08 0.08 --path --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["path_collides"].get<bool>());
  EXPECT_EQ(j["path_first_segment"], 0);
  EXPECT_NEAR(j["path_fraction"].get<double>(), (0.96 - 0.5) / 1.1, 0.05 / 1.1 + 1e-9);
  EXPECT_EQ(j["path_cell"][0], 10);

  // Capsule lying along y (rotated 90 degrees about x) next to the wall, with and without margin.
  writeText(wp, "0.9 0 0 0.7071067811865476 0 0 0.7071067811865476\n");
  r = runCli(dir, "collide '" + map + "' --waypoints '" + wp + "' --capsule 0.05 0.6 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["colliding"], 0);
  r = runCli(dir, "collide '" + map + "' --waypoints '" + wp +
                      "' --capsule 0.05 0.6 --margin 0.06 --count-cells --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["colliding"], 1);
  EXPECT_GT(j["colliding_cells"][0].get<int>(), 1);

  // Far from the wall: free, unless unknown space counts.
  writeText(wp, "-3 -3 -3 0 0 0 1\n");
  r = runCli(dir, "collide '" + map + "' --waypoints '" + wp + "' --sphere 0.2 --json");
  EXPECT_EQ(nlohmann::json::parse(r.out)["colliding"], 0);
  r = runCli(
      dir, "collide '" + map + "' --waypoints '" + wp + "' --sphere 0.2 --unknown-occupied --json");
  EXPECT_EQ(nlohmann::json::parse(r.out)["colliding"], 1);
}

TEST(CliCollide, MeshFromObjWithScale) {
  const std::string dir = testDir();
  const std::string map = wallMap(dir), wp = dir + "/wp.txt", obj = dir + "/cube.obj";
  geometry::writeObj(geometry::test::boxSolid({-1, -1, -1}, {1, 1, 1}), obj);
  // A 2 m cube scaled to 0.5 m, 0.3 m in front of the wall: free; scaled to 1 m: it cuts in.
  writeText(wp, "0.7 0.05 0.05 0 0 0 1\n");
  auto r = runCli(dir, "collide '" + map + "' --waypoints '" + wp + "' --mesh '" + obj +
                           "' --mesh-scale 0.25 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["colliding"], 0);
  r = runCli(dir, "collide '" + map + "' --waypoints '" + wp + "' --mesh '" + obj +
                      "' --mesh-scale 0.5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["colliding"], 1);
}

TEST(CliCollide, PngShowsFreeAndCollidingPosesAndThePath) {
  const std::string dir = testDir();
  const std::string map = wallMap(dir), wp = dir + "/png_wp.txt", png = dir + "/collide.png";
  // Free at x = 0.5, colliding at the wall (x = 1.05), free beyond it at x = 1.6.
  writeText(wp, "0.5 0.05 0.05 0 0 0 1\n1.05 0.05 0.05 0 0 0 1\n1.6 0.05 0.05 0 0 0 1\n");
  const auto r = runCli(dir, "collide '" + map + "' --waypoints '" + wp +
                                 "' --box 0.2 0.2 0.2 --path --backend cpu --png '" + png + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const test::Image img = test::readPng(png);
  ASSERT_GT(img.width, 0);
  // Count the footprint colours: green outlines for the two free poses, red for the colliding
  // one and the path's first collision.
  int green = 0, red = 0, white = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Rgb c = img.at(x, y);
      green += c == Rgb{40, 200, 60};
      red += c == Rgb{235, 30, 30};
      white += c == Rgb{255, 255, 255};
    }
  EXPECT_GT(green, 50);
  EXPECT_GT(red, 50);
  EXPECT_GT(white, 20);  // the path's segments
  // The image spans the waypoints +- (bounding radius + 2 m), whole 0.1 m voxel columns: the
  // free pose's outline runs along x = 0.4 m in green, the colliding pose's along x = 0.95 m
  // in red.
  const double pad_m = std::sqrt(0.03) + 2.0;
  const int lo_x = int(std::floor((0.5 - pad_m) / 0.1)),
            hi_x = int(std::floor((1.6 + pad_m) / 0.1));
  const int px_per_voxel = img.width / (hi_x - lo_x + 1);
  ASSERT_GT(px_per_voxel, 0);
  const auto column = [&](double x_m) {
    return int(std::lround((x_m / 0.1 - lo_x) * px_per_voxel));
  };
  int green_at_free = 0, red_at_hit = 0;
  for (int y = 0; y < img.height; ++y)
    for (int dx = -1; dx <= 1; ++dx) {
      const int xf = column(0.4) + dx, xh = column(0.95) + dx;
      if (xf >= 0 && xf < img.width) green_at_free += img.at(xf, y) == Rgb{40, 200, 60};
      if (xh >= 0 && xh < img.width) red_at_hit += img.at(xh, y) == Rgb{235, 30, 30};
    }
  EXPECT_GT(green_at_free, 5);
  EXPECT_GT(red_at_hit, 5);
}

TEST(CliCollide, BadInputIsRefusedWithOneLine) {
  const std::string dir = testDir();
  const std::string map = wallMap(dir), good = dir + "/good.txt", obj = dir + "/flat.obj";
  writeText(good, "0 0 0 0 0 0 1\n");
  writeText(dir + "/short.txt", "0 0 0 0 0 1\n");
  writeText(dir + "/text.txt", "0 0 zero 0 0 0 1\n");
  writeText(dir + "/norm.txt", "0 0 0 0 0 0 1.00001\n");
  writeText(dir + "/empty.txt", "# nothing\n");
  writeText(obj, "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n");
  writeText(dir + "/broken.obj", "v 0 0 0\nf 1 2 3\n");
  const std::string base = "collide '" + map + "' --waypoints ";
  struct Case {
    std::string args;
    int exit_code;
  };
  const Case cases[] = {
      {base + "'" + dir + "/short.txt' --sphere 0.1", 1},
      {base + "'" + dir + "/text.txt' --sphere 0.1", 1},
      {base + "'" + dir + "/norm.txt' --sphere 0.1", 1},
      {base + "'" + dir + "/empty.txt' --sphere 0.1", 1},
      {base + "'" + dir + "/missing.txt' --sphere 0.1", 1},
      {base + "'" + good + "' --mesh '" + obj + "'", 1},
      {base + "'" + good + "' --mesh '" + dir + "/broken.obj'", 1},
      {base + "'" + good + "' --mesh '" + dir + "/missing.obj'", 1},
      {"collide '" + dir + "/missing.fgm' --waypoints '" + good + "' --sphere 0.1", 1},
      {base + "'" + good + "'", 2},
      {base + "'" + good + "' --sphere 0.1 --box 1 1 1", 2},
      {base + "'" + good + "' --box 1 -1 1", 2},
      {base + "'" + good + "' --sphere 0", 2},
      {base + "'" + good + "' --capsule 0.1", 2},
      {base + "'" + good + "' --sphere 0.1 --margin -0.1", 2},
      {base + "'" + good + "' --sphere 0.1 --backend gpu", 2},
      {base + "'" + good + "' --sphere 0.1 --png '" + dir + "/out.jpg'", 2},
      {base + "'" + good + "' --mesh '" + obj + "' --mesh-scale 0", 2},
  };
  std::vector<Case> all(std::begin(cases), std::end(cases));
  std::string why;
  if (cudaDeviceName(0, &why).empty())  // cuda requested without a device
    all.push_back({base + "'" + good + "' --sphere 0.1 --backend cuda", 2});
  for (const Case& k : all) {
    const auto r = runCli(dir, k.args);
    EXPECT_EQ(r.exit_code, k.exit_code) << k.args << "\n" << r.err;
    EXPECT_EQ(r.err.find("fragg_map: error: "), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

}  // namespace
}  // namespace fragg
