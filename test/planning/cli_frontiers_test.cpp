// `fragg_map frontiers` run as a user would: the JSON against the library on the same saved
// map, filters, viewpoints, and bad arguments refused with one line and exit code 2; and
// `fragg_map render --frontiers`: frontier colours exactly on the frontier cells' columns, the
// rest of the map faded, the viewpoints drawn where `frontiers --json` puts them.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "fragg_map/map.h"
#include "fragg_map/planning/coarse_map.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "interop_test_util.h"
#include "png_test_util.h"

namespace fragg {
namespace {

using test::runCli;
using test::testDir;

/// A free corridor 4 x 1 x 1 m (0.1 m cells) in unknown space with an occupied wall across
/// its -x end: frontier cells on its sides and at its +x end.
std::string corridorMap(const std::string& dir, Map* out) {
  MapParams params;
  params.resolution_m = 0.1;
  Map map(params);
  map.writeCells([](CellWriter& w) {
    for (int z = 0; z < 10; ++z)
      for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 40; ++x) w.set({x, y, z}, x == 0 ? Cell{1, 3000} : Cell{0, -2000});
  });
  const std::string path = dir + "/corridor.fgm";
  map.save(path);
  *out = Map::load(path, Backend::kCpu);
  return path;
}

TEST(CliFrontiers, JsonMatchesTheLibrary) {
  const std::string dir = testDir();
  Map map;
  const std::string path = corridorMap(dir, &map);
  auto r = runCli(dir, "frontiers '" + path + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  const auto cells = planning::findFrontierCells(map);
  EXPECT_EQ(j["frontier_cells"].get<size_t>(), cells.size());
  planning::FrontierClusterer clusterer;
  const auto clusters = clusterer.cluster(map, cells);
  ASSERT_EQ(j["clusters"].size(), clusters.size());
  ASSERT_GT(clusters.size(), 1u) << "the 4 m corridor is split at 3 m";
  uint64_t sum = 0;
  for (size_t i = 0; i < clusters.size(); ++i) {
    const auto& jc = j["clusters"][i];
    EXPECT_EQ(jc["cells"].get<size_t>(), clusters[i].cells.size());
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(jc["centroid"][a].get<double>(), clusters[i].centroid_m[a], 1e-9);
      EXPECT_NEAR(jc["min"][a].get<double>(), clusters[i].min_m[a], 1e-9);
      EXPECT_NEAR(jc["max"][a].get<double>(), clusters[i].max_m[a], 1e-9);
    }
    EXPECT_TRUE(jc["viewpoints"].empty()) << "none asked for";
    sum += jc["cells"].get<uint64_t>();
  }
  EXPECT_EQ(sum, cells.size());

  // A box around the +x end and viewpoints from inside the corridor.
  r = runCli(dir, "frontiers '" + path +
                      "' --box 3.9 -1 -1 4.1 2 2 --viewpoints 2 --radii 1 2 --clearance 0.1 "
                      "--robot 1 0.5 0.5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["frontier_cells"], 100) << "the end face, 10 x 10 cells";
  ASSERT_EQ(j["clusters"].size(), 1u);
  const auto& views = j["clusters"][0]["viewpoints"];
  ASSERT_EQ(views.size(), 2u);
  for (const auto& v : views) {
    EXPECT_GT(v["gain_bits"].get<double>(), 0.0);
    EXPECT_LT(v["position"][0].get<double>(), 3.9) << "inside the corridor";
    EXPECT_GE(views[0]["gain_per_metre"].get<double>(), v["gain_per_metre"].get<double>());
  }

  r = runCli(dir, "frontiers '" + path + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(std::to_string(cells.size()) + " frontier cells"), std::string::npos)
      << r.out;
  EXPECT_EQ(nlohmann::json::parse(runCli(dir, "frontiers '" + path + "' --json").out)
                .count("coarse_cells"),
            0u)
      << "the default JSON has no new key";

  // On the coarse map: the library's answer on planning::coarseStateMap, keys saying so.
  r = runCli(dir, "frontiers '" + path + "' --coarse-cells 4 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  const Map coarse = planning::coarseStateMap(map, 4);
  const auto coarse_cells = planning::findFrontierCells(coarse);
  ASSERT_GT(coarse_cells.size(), 0u);
  EXPECT_LT(coarse_cells.size(), cells.size());
  EXPECT_EQ(j["frontier_cells"].get<size_t>(), coarse_cells.size());
  EXPECT_EQ(j["coarse_cells"].get<int>(), 4);
  EXPECT_NEAR(j["frontier_resolution_m"].get<double>(), 4 * map.resolution(), 1e-12);
  EXPECT_EQ(j["clusters"].size(),
            planning::FrontierClusterer().cluster(coarse, coarse_cells).size());
}

TEST(CliFrontiers, BadArgumentsExitTwo) {
  const std::string dir = testDir();
  Map map;
  const std::string path = corridorMap(dir, &map);
  for (const std::string args :
       {" --box 1 1 1 0 0 0", " --box nan 0 0 1 1 1", " --viewpoints -1", " --min-cluster 0",
        " --viewpoints 1 --radii 0", " --sensor sonar", " --viewpoints 1 --max-range -2",
        " --height 2 1", " --coarse-cells 3", " --coarse-cells 0"}) {
    const auto r = runCli(dir, "frontiers '" + path + "'" + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find("rror"), std::string::npos) << args << ": " << r.err;
  }
  const auto r = runCli(dir, "frontiers '" + dir + "/missing.fgm'");
  EXPECT_EQ(r.exit_code, 1) << r.err;
}

/// A closed free room 4 x 1 x 1 m (0.1 m cells, x 1..39, y 0..9, z 0..9) under an occupied
/// ceiling (z 10) over an occupied floor (z -1), closed by a wall at x 0 and open (unknown)
/// on its two long sides and its +x end: the frontier cells are the rows y 0 and y 9 and the
/// end x 39; every column of the room has the ceiling on top.
std::string roomMap(const std::string& dir) {
  MapParams params;
  params.resolution_m = 0.1;
  Map map(params);
  map.writeCells([](CellWriter& w) {
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 40; ++x)
        for (int z = -1; z <= 10; ++z)
          w.set({x, y, z}, (x == 0 || z == -1 || z == 10) ? Cell{1, 3000} : Cell{0, -2000});
  });
  const std::string path = dir + "/room.fgm";
  map.save(path);
  return path;
}

TEST(CliRenderFrontiers, FrontierColoursOnFrontierColumnsAndViewpoints) {
  const std::string dir = testDir();
  const std::string path = roomMap(dir);
  const std::string options = " --viewpoints 1 --radii 0.5 1 --clearance 0";
  const int scale = 8;
  auto r = runCli(dir, "render '" + path + "' -o '" + dir + "/plain.png' --scale 8 --no-legend");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runCli(dir, "render '" + path + "' -o '" + dir +
                      "/frontiers.png' --scale 8 --no-legend --frontiers" + options);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("frontiers: 860 cells"), std::string::npos) << r.out;
  r = runCli(dir, "frontiers '" + path + "' --json" + options);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["frontier_cells"].get<int>(), 2 * 39 * 10 + 8 * 10);
  const size_t clusters = j["clusters"].size();
  ASSERT_GT(clusters, 1u) << "the 4 m U is split at 3 m";
  ASSERT_LE(clusters, 12u) << "more clusters than colours";

  const test::Image plain = test::readPng(dir + "/plain.png");
  const test::Image drawn = test::readPng(dir + "/frontiers.png");
  ASSERT_EQ(plain.width, 40 * scale);
  ASSERT_EQ(plain.height, 10 * scale);
  ASSERT_EQ(drawn.width, plain.width);
  ASSERT_EQ(drawn.height, plain.height);
  // Image position of a map point (x right from key x 0, y down from key y 9's top edge).
  const auto pixel = [&](double x_m, double y_m) {
    return std::make_pair(x_m / 0.1 * scale, (10.0 - y_m / 0.1) * scale);
  };
  std::vector<std::pair<double, double>> views;
  for (const auto& c : j["clusters"]) {
    ASSERT_EQ(c["viewpoints"].size(), 1u) << c.dump();
    const auto& v = c["viewpoints"][0];
    views.push_back(pixel(v["position"][0].get<double>(), v["position"][1].get<double>()));
  }
  const auto near_view = [&](int px, int py) {
    for (const auto& [vx, vy] : views)
      if (std::hypot(px + 0.5 - vx, py + 0.5 - vy) < 22.0) return true;
    return false;
  };
  std::set<std::tuple<int, int, int>> frontier_colours;
  int frontier_pixels = 0, interior_pixels = 0;
  for (int py = 0; py < plain.height; ++py)
    for (int px = 0; px < plain.width; ++px) {
      if (near_view(px, py)) continue;
      const int kx = px / scale, ky = 9 - py / scale;
      const bool frontier = kx >= 1 && (ky == 0 || ky == 9 || kx == 39);
      // The map is faded to (c + 128) / 2 per channel, within [64, 191]; the clusters'
      // colours are saturated (a channel 0 or 255).
      const Rgb a = plain.at(px, py), b = drawn.at(px, py);
      const Rgb faded{static_cast<uint8_t>((a.r + 128) / 2), static_cast<uint8_t>((a.g + 128) / 2),
                      static_cast<uint8_t>((a.b + 128) / 2)};
      if (frontier) {
        EXPECT_TRUE(b.r == 0 || b.r == 255 || b.g == 0 || b.g == 255 || b.b == 0 || b.b == 255)
            << "frontier column " << kx << " " << ky << " not drawn";
        frontier_colours.insert({b.r, b.g, b.b});
        ++frontier_pixels;
      } else {
        EXPECT_EQ(b, faded) << "column " << kx << " " << ky << " holds no frontier cell";
        ++interior_pixels;
      }
    }
  EXPECT_GT(frontier_pixels, 1000);
  EXPECT_GT(interior_pixels, 1000);
  EXPECT_EQ(frontier_colours.size(), clusters) << "one colour per cluster";
  // The viewpoints: white discs where `frontiers --json` puts them.
  for (const auto& [vx, vy] : views)
    EXPECT_EQ(drawn.at(static_cast<int>(vx), static_cast<int>(vy)), (Rgb{255, 255, 255}));
}

TEST(CliRenderFrontiers, BadArgumentsExitTwo) {
  const std::string dir = testDir();
  const std::string path = roomMap(dir);
  const std::string base = "render '" + path + "' -o '" + dir + "/x.png'";
  for (const std::string args :
       {" --min-cluster 3", " --viewpoints 2", " --frontiers --view slice --z 0.5",
        " --frontiers --viewpoints -1", " --frontiers --box 1 1 1 0 0 0",
        " --frontiers --box nan 0 0 1 1 1", " --frontiers --min-cluster 0",
        " --frontiers --sensor sonar", " --frontiers --radii 0"}) {
    const auto r = runCli(dir, base + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find("rror"), std::string::npos) << args << ": " << r.err;
  }
  EXPECT_FALSE(test::fileExists(dir + "/x.png"));
}

}  // namespace
}  // namespace fragg
