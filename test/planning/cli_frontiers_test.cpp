// `fragg_map frontiers` run as a user would: the JSON against the library on the same saved
// map, filters, viewpoints, and bad arguments refused with one line and exit code 2.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "fragg_map/map.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "interop_test_util.h"

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
}

TEST(CliFrontiers, BadArgumentsExitTwo) {
  const std::string dir = testDir();
  Map map;
  const std::string path = corridorMap(dir, &map);
  for (const std::string args : {" --box 1 1 1 0 0 0", " --box nan 0 0 1 1 1", " --viewpoints -1",
                                 " --min-cluster 0", " --viewpoints 1 --radii 0", " --sensor sonar",
                                 " --viewpoints 1 --max-range -2", " --height 2 1"}) {
    const auto r = runCli(dir, "frontiers '" + path + "'" + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find("rror"), std::string::npos) << args << ": " << r.err;
  }
  const auto r = runCli(dir, "frontiers '" + dir + "/missing.fgm'");
  EXPECT_EQ(r.exit_code, 1) << r.err;
}

}  // namespace
}  // namespace fragg
