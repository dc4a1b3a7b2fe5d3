// The fragg_map tool's export, render and compare subcommands, run as a user would.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "interop_test_util.h"

namespace fragg {
namespace {

using test::fileExists;
using test::listDir;
using test::paramsAt;
using test::readBytes;
using test::runCli;
using test::RunResult;
using test::setCell;
using test::testDir;
using test::writeBytes;

/// In `dir`: map.fgm (a few free and occupied cells at 5 cm), coarse.fgm (10 cm),
/// empty.fgm, corrupt.fgm, map.txt; and an empty out/ directory for the outputs.
void writeInputs(const std::string& dir) {
  Map map(paramsAt(0.05));
  for (int x = -4; x < 12; ++x)
    for (int y = -3; y < 5; ++y) setCell(map, {x, y, 0}, map.model().min_fx);
  for (int x = -4; x < 12; ++x) setCell(map, {x, 5, 2}, map.model().max_fx);
  setCell(map, {0, 0, 6}, map.model().max_fx);
  map.save(dir + "/map.fgm");
  Map coarse(paramsAt(0.1));
  setCell(coarse, {1, 1, 1}, 900);
  coarse.save(dir + "/coarse.fgm");
  Map(paramsAt(0.05)).save(dir + "/empty.fgm");
  writeBytes(dir + "/corrupt.fgm", "FRAGGMAP but not really a map file\n");
  writeBytes(dir + "/corrupt.bt", "# Octomap OcTree binary file\nsize 3\nres 0.05\ndata\n\x03");
  writeBytes(dir + "/map.txt", "0 0 0\n");
  ASSERT_EQ(std::system(("mkdir -p '" + dir + "/out'").c_str()), 0);
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testDir();
    writeInputs(dir_);
  }
  std::string in(const std::string& name) const { return "'" + dir_ + "/" + name + "'"; }
  std::string out(const std::string& name) const { return dir_ + "/out/" + name; }
  RunResult run(const std::string& args) const { return runCli(dir_, args); }
  std::string dir_;
};

TEST_F(Cli, ExportsPlyAndPcd) {
  RunResult r = run("export " + in("map.fgm") + " --format ply -o " + out("map.ply"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // nothing on stderr (liboctomap's debug lines included)
  EXPECT_NE(r.out.find("17 occupied voxel centres"), std::string::npos) << r.out;
  EXPECT_EQ(readBytes(out("map.ply")).rfind("ply\n", 0), 0u);

  r = run("export " + in("map.fgm") + " -o " + out("map.pcd"));  // format from the extension
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // nothing on stderr (liboctomap's debug lines included)
  EXPECT_NE(readBytes(out("map.pcd")).find("POINTS 17\n"), std::string::npos);
}

TEST_F(Cli, RendersTopViewAndSlice) {
  RunResult r = run("render " + in("map.fgm") + " -o " + out("top.png") + " --scale 2");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // nothing on stderr (liboctomap's debug lines included)
  EXPECT_NE(r.out.find("32 x 18 px"), std::string::npos) << r.out;  // x -4..11, y -3..5
  EXPECT_NE(r.out.find("with the legend below, the PNG is"), std::string::npos) << r.out;
  EXPECT_EQ(readBytes(out("top.png")).substr(1, 3), "PNG");
  const std::string with_legend = readBytes(out("top.png"));
  r = run("render " + in("map.fgm") + " -o " + out("bare.png") + " --scale 2 --no-legend");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("32 x 18 px"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("legend"), std::string::npos) << r.out;
  EXPECT_LT(readBytes(out("bare.png")).size(), with_legend.size());

  r = run("render " + in("map.fgm") + " -o " + out("slice.png") + " --view slice --z 0.01");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // nothing on stderr (liboctomap's debug lines included)
  EXPECT_TRUE(fileExists(out("slice.png")));
}

TEST_F(Cli, ComparePrintsFiguresAndJson) {
  RunResult r = run("compare " + in("map.fgm") + " " + in("map.fgm"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // nothing on stderr (liboctomap's debug lines included)
  EXPECT_NE(r.out.find("known in both:   145 cells, same state: 145 (100.000 %)"),
            std::string::npos)
      << r.out;

  r = run("compare " + in("map.fgm") + " " + in("empty.fgm") + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // nothing on stderr (liboctomap's debug lines included)
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["threshold"], "band");
  EXPECT_EQ(j["known_in_a"], 145);
  EXPECT_EQ(j["known_in_b"], 0);
  EXPECT_EQ(j["known_in_either"], 145);
  EXPECT_TRUE(j["agreement_in_both"].is_null());
  EXPECT_DOUBLE_EQ(j["agreement_in_either"].get<double>(), 0.0);
  EXPECT_EQ(j["confusion"]["occupied"]["unknown"], 17);
  EXPECT_EQ(j["confusion"]["free"]["unknown"], 128);
}

#ifdef FRAGG_CLI_HAS_OCTOMAP
TEST_F(Cli, ExportsBtThatAgreesWithTheMap) {
  RunResult r = run("export " + in("map.fgm") + " --format bt -o " + out("map.bt"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // nothing on stderr (liboctomap's debug lines included)
  r = run("compare " + in("map.fgm") + " '" + out("map.bt") + "' --json --octomap-threshold");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // nothing on stderr (liboctomap's debug lines included)
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["threshold"], "octomap");
  EXPECT_EQ(j["known_in_both"], 145);
  EXPECT_DOUBLE_EQ(j["agreement_in_either"].get<double>(), 1.0);
  // And a .bt renders like any map.
  r = run("render '" + out("map.bt") + "' -o " + out("bt.png"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // nothing on stderr (liboctomap's debug lines included)
}
#endif

struct BadCase {
  std::string args;  // "{in}" and "{out}" stand for the input and output directories
  int exit_code;
};

std::string expand(std::string s, const std::string& in_dir, const std::string& out_dir) {
  for (size_t at; (at = s.find("{in}")) != std::string::npos;) s.replace(at, 4, in_dir);
  for (size_t at; (at = s.find("{out}")) != std::string::npos;) s.replace(at, 5, out_dir);
  return s;
}

TEST_F(Cli, BadArgumentsAndInputsFailCleanly) {
  std::vector<BadCase> cases = {
      {"export {in}/missing.fgm --format ply -o {out}/x.ply", 1},
      {"export {in}/map.fgm --format xyz -o {out}/x.xyz", 2},
      {"export {in}/map.fgm -o {out}/x.txt", 2},
      {"export {in}/map.fgm --format ply -o {out}/no/such/dir/x.ply", 1},
      {"export {in}/map.fgm --format ply -o {in}/map.fgm/x.ply", 1},
      {"export {in}/map.fgm --format ply", 2},
      {"export {in}/map.txt --format ply -o {out}/x.ply", 2},
      {"export {in}/corrupt.fgm --format pcd -o {out}/x.pcd", 1},
      {"export {in} --format pcd -o {out}/x.pcd", 2},
      {"render {in}/map.fgm -o {out}/x.jpg", 2},
      {"render {in}/map.fgm -o {out}/x.png --view slice", 2},
      {"render {in}/map.fgm -o {out}/x.png --z 1", 2},
      {"render {in}/map.fgm -o {out}/x.png --view side", 2},
      {"render {in}/map.fgm -o {out}/x.png --scale 0", 2},
      {"render {in}/map.fgm -o {out}/x.png --scale 8 --max-size 16 --no-downscale", 2},
      {"render {in}/map.fgm -o {out}/x.png --crop 1 2 3", 2},
      {"render {in}/map.fgm -o {out}/no/such/dir/x.png", 1},
      {"render {in}/empty.fgm -o {out}/x.png", 2},
      {"render {in}/missing.fgm -o {out}/x.png", 1},
      {"compare {in}/map.fgm {in}/missing.fgm", 1},
      {"compare {in}/map.fgm {in}/coarse.fgm", 2},
      {"compare {in}/map.fgm {in}/corrupt.fgm --json", 1},
      {"compare {in}/map.fgm", 2},
      {"frobnicate {in}/map.fgm", 2},
  };
#ifdef FRAGG_CLI_HAS_OCTOMAP
  cases.push_back({"export {in}/corrupt.bt --format ply -o {out}/x.ply", 1});
  cases.push_back({"export {in}/map.fgm --format bt -o {out}/no/such/dir/x.bt", 1});
  cases.push_back({"compare {in}/corrupt.bt {in}/map.fgm", 1});
#endif
  for (const BadCase& c : cases) {
    const std::string args = expand(c.args, dir_, dir_ + "/out");
    SCOPED_TRACE(args);
    const RunResult r = run(args);
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    // One line naming the problem, nothing on stdout.
    EXPECT_EQ(r.err.rfind("fragg_map: error: ", 0), 0u) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
    EXPECT_EQ(r.out, "");
    EXPECT_TRUE(listDir(dir_ + "/out").empty()) << "left behind: " << listDir(dir_ + "/out")[0];
  }
  std::vector<std::string> inputs = listDir(dir_);
  EXPECT_EQ(inputs.size(), 7u) << "a file appeared beside the inputs";
}

TEST_F(Cli, UnknownOrMissingCommandIsNamedAndTheCommandsListed) {
  const char* kCommands =
      "build, correct, truncate, merge, stats, export, render, compare, eval, octomap-build, "
      "collide, frontiers, convert-store";
  RunResult r = run("frobnicate " + in("map.fgm"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, std::string("fragg_map: error: unknown command 'frobnicate'; the commands "
                               "are: ") +
                       kCommands + " (see --help)\n");
  r = run("");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err,
            std::string("fragg_map: error: give a command: ") + kCommands + " (see --help)\n");
  // Known commands and options before a command still reach CLI11.
  r = run("--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("truncate"), std::string::npos);
  r = run("stats " + in("map.fgm"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

}  // namespace
}  // namespace fragg
