// Durability of the page store: `fragg_map build --page-store` is killed with SIGKILL at
// different moments, the store reopens to its last commit (every record decodes, and the map it
// holds equals the map of the first K scans for the K it records), and the next build continues
// it to the full map. Meanwhile this process reads the store while the build writes it.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/store/page_stores.h"
#include "paging_scenes.h"

extern char** environ;

namespace fragg::test {
namespace {

constexpr int kScans = 120;

/// The corridor drive as a KITTI sequence (velodyne/*.bin, poses.txt, calib.txt).
void writeKittiSequence(const std::string& dir) {
  mkdir((dir + "/velodyne").c_str(), 0755);
  FILE* poses = std::fopen((dir + "/poses.txt").c_str(), "w");
  for (int i = 0; i < kScans; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    const PointCloud cloud = corridorScan(T);
    char name[64];
    std::snprintf(name, sizeof(name), "/velodyne/%06d.bin", i);
    FILE* f = std::fopen((dir + name).c_str(), "wb");
    for (const Eigen::Vector3f& p : cloud.points_S) {
      const float v[4] = {p.x(), p.y(), p.z(), 0.0f};
      std::fwrite(v, sizeof(v), 1, f);
    }
    std::fclose(f);
    const Eigen::Matrix<double, 3, 4> m = T.matrix().topRows<3>();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) std::fprintf(poses, "%.17g ", m(r, c));
    std::fprintf(poses, "\n");
  }
  std::fclose(poses);
  writeBytes(dir + "/calib.txt", "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n");
}

/// The maps of the first K scans, K growing (as the store's committed scans must).
class Reference {
 public:
  explicit Reference(const std::string& dataset) : map_(corridorParams()) {
    auto source = openDataset(dataset);
    Scan s;
    while (source->next(s)) scans_.push_back(s);
  }
  const Map& at(size_t k) {
    EXPECT_GE(k, next_) << "the store went back from " << next_ << " to " << k << " scans";
    for (; next_ < k && next_ < scans_.size(); ++next_)
      map_.insert(scans_[next_].cloud, scans_[next_].T_map_sensor, corridorSensor());
    return map_;
  }
  size_t size() const { return scans_.size(); }

 private:
  std::vector<Scan> scans_;
  Map map_;
  size_t next_ = 0;
};

/// Reads the store (read-only, one snapshot) and checks it against the reference; returns K.
size_t checkStore(const std::string& path, Reference& ref) {
  const Map stored = Map::loadPageStore(*openPageStore(path, /*read_only=*/true));
  const size_t k = stored.scanCount();
  std::string why;
  EXPECT_TRUE(sameBlocks(stored, ref.at(k), &why)) << "after " << k << " scans: " << why;
  return k;
}

pid_t launchBuild(const std::string& dataset, const std::string& store, const std::string& log) {
  std::vector<std::string> args = {FRAGG_CLI_PATH,
                                   "build",
                                   dataset,
                                   "--page-store",
                                   store,
                                   "--page-budget-mb",
                                   "10",
                                   "--page-radius",
                                   "4",
                                   "--commit-every",
                                   "1",
                                   "--resolution",
                                   "0.1",
                                   "--max-range",
                                   "15",
                                   "--backend",
                                   "cpu",
                                   "--threads",
                                   "1"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

class StoreCrash : public ::testing::TestWithParam<PageStoreKind> {
 protected:
  void SetUp() override {
    if (GetParam() == PageStoreKind::kLmdb && !lmdbAvailable()) GTEST_SKIP() << "no LMDB";
  }
};

TEST_P(StoreCrash, KilledBuildsReopenAtTheirLastCommitAndContinue) {
  const std::string dir = testDir();
  writeKittiSequence(dir);
  const std::string store = dir + (GetParam() == PageStoreKind::kLmdb ? "/map.lmdb" : "/map.db");
  Reference ref(dir);
  ASSERT_EQ(ref.size(), static_cast<size_t>(kScans));

  size_t committed = 0;
  int kills = 0, concurrent_reads = 0;
  // Kill once the store holds at least `after` scans, `delay_ms` later (during a scan or a
  // commit; the moments differ from round to round).
  const std::vector<std::pair<size_t, int>> rounds = {{5, 0}, {20, 3}, {40, 11}, {60, 1}, {80, 7}};
  for (const auto& [after, delay_ms] : rounds) {
    const pid_t pid = launchBuild(dir, store, dir + "/build.log");
    ASSERT_GT(pid, 0);
    int status = 0;
    bool exited = false;
    // Read the store while the build writes it, until it holds `after` scans.
    while (!exited) {
      if (waitpid(pid, &status, WNOHANG) == pid) {
        exited = true;
        break;
      }
      if (access(store.c_str(), F_OK) == 0) {
        size_t k = 0;
        try {
          k = checkStore(store, ref);
          ++concurrent_reads;
        } catch (const IoError& e) {
          // Only before the first build's first commit: a store file without a map yet.
          EXPECT_EQ(concurrent_reads, 0) << e.what();
          EXPECT_EQ(committed, 0u) << e.what();
        }
        if (k >= after) break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    if (!exited) {
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
      kill(pid, SIGKILL);
      ASSERT_EQ(waitpid(pid, &status, 0), pid);
      if (WIFSIGNALED(status)) ++kills;
    }
    // Reopened: the last commit, never corrupt, never behind what a reader saw.
    const size_t k = checkStore(store, ref);
    EXPECT_GE(k, committed);
    committed = k;
    if (committed == static_cast<size_t>(kScans)) break;
  }
  EXPECT_GE(kills, 3) << "the build finished before it could be killed mid-way";
  EXPECT_GT(concurrent_reads, 5);
  EXPECT_LT(committed, static_cast<size_t>(kScans));

  // The last build runs to the end: the full map.
  const pid_t pid = launchBuild(dir, store, dir + "/build.log");
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << readBytes(dir + "/build.log");
  EXPECT_EQ(checkStore(store, ref), static_cast<size_t>(kScans));
}

/// Runs the CLI; returns its exit status, stdout and stderr in `out`.
int runCli(const std::string& dir, const std::string& args, std::string* out) {
  const std::string log = dir + "/cli.log";
  const int rc = std::system(
      (std::string("'") + FRAGG_CLI_PATH + "' " + args + " > '" + log + "' 2>&1").c_str());
  *out = readBytes(log);
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(CliPaging, StoresAreReadWhereMapsAreAndBadFlagsAreRefused) {
  const std::string dir = testDir();
  writeKittiSequence(dir);
  const std::string common =
      "'" + dir + "' --resolution 0.1 --max-range 15 --backend cpu --scans 12";
  std::string out;
  ASSERT_EQ(runCli(dir, "build " + common + " -o '" + dir + "/mem.fgm'", &out), 0) << out;
  ASSERT_EQ(runCli(dir,
                   "build " + common + " --page-store '" + dir +
                       "/s.lmdb' --page-budget-mb 10 --page-radius 3 --page-low-water 0.5 "
                       "--read-ahead-rays 0 --json",
                   &out),
            0)
      << out;
  for (const char* field : {"\"peak_resident_blocks\"", "\"pages_written\"", "\"pages_read\"",
                            "\"low_water\":0.5", "\"read_ahead_rays\":0"})
    EXPECT_NE(out.find(field), std::string::npos) << field << " missing in " << out;
  // compare accepts the store as a map: every cell agrees with the in-memory build's.
  ASSERT_EQ(runCli(dir, "compare '" + dir + "/s.lmdb' '" + dir + "/mem.fgm' --json", &out), 0)
      << out;
  EXPECT_NE(out.find("\"agreement_in_either\":1.0"), std::string::npos) << out;
  ASSERT_EQ(runCli(dir, "stats '" + dir + "/s.lmdb'", &out), 0) << out;
  EXPECT_NE(out.find("scans        12"), std::string::npos) << out;
  // A paged build's malloc settings (the default) or glibc's own (--heap-defaults): the same
  // map file, byte for byte, and the in-memory build's.
  for (const char* heap : {"h1", "h2"}) {
    const std::string flag = std::string(heap) == "h1" ? " --heap-defaults" : "";
    ASSERT_EQ(runCli(dir,
                     "build " + common + " --page-store '" + dir + "/" + heap +
                         ".lmdb' --page-budget-mb 10 --page-radius 3 -o '" + dir + "/" + heap +
                         ".fgm'" + flag,
                     &out),
              0)
        << out;
  }
  EXPECT_EQ(readBytes(dir + "/h1.fgm"), readBytes(dir + "/h2.fgm"));
  EXPECT_EQ(readBytes(dir + "/h2.fgm"), readBytes(dir + "/mem.fgm"));

  EXPECT_EQ(runCli(dir, "build " + common + " --page-budget-mb 5 -o '" + dir + "/x.fgm'", &out), 2);
  EXPECT_NE(out.find("--page-store"), std::string::npos) << out;
  EXPECT_EQ(runCli(dir, "build " + common, &out), 2);
  EXPECT_NE(out.find("-o"), std::string::npos) << out;
  EXPECT_EQ(
      runCli(dir, "build " + common + " --page-store '" + dir + "/t.db' --page-radius -1", &out),
      2);
  EXPECT_NE(out.find("radius"), std::string::npos) << out;
  EXPECT_EQ(runCli(dir, "build " + common + " --page-store '" + dir + "/t.db' --page-low-water 1.5",
                   &out),
            2);
  EXPECT_NE(out.find("low_water"), std::string::npos) << out;
  EXPECT_EQ(runCli(dir, "stats '" + dir + "/missing.db'", &out), 1);
  EXPECT_NE(out.find("no such file"), std::string::npos) << out;
}

TEST(CliPaging, BatchesStopAtTheScanLimitAndAResumedStoreMatchesOneBuild) {
  // The CLI inserts batches of up to 16 scans (Map::insertSequence): a limit inside a batch, and a
  // store continued from a count that is not a multiple of 16, give the one build's map.
  const std::string dir = testDir();
  writeKittiSequence(dir);
  const std::string input = "'" + dir + "' --resolution 0.1 --max-range 15 --backend cpu";
  const std::string store = "'" + dir + "/r.db'";
  std::string out;
  ASSERT_EQ(runCli(dir, "build " + input + " --scans 37 -o '" + dir + "/all.fgm' --json", &out), 0)
      << out;
  EXPECT_NE(out.find("\"scans\":37"), std::string::npos) << out;
  ASSERT_EQ(runCli(dir, "build " + input + " --scans 21 --page-store " + store, &out), 0) << out;
  ASSERT_EQ(runCli(dir, "build " + input + " --scans 37 --page-store " + store + " --json", &out),
            0)
      << out;
  EXPECT_NE(out.find("\"scans\":16"), std::string::npos) << "the 16 scans after 21: " << out;
  ASSERT_EQ(runCli(dir, "stats " + store, &out), 0) << out;
  EXPECT_NE(out.find("scans        37"), std::string::npos) << out;
  ASSERT_EQ(runCli(dir, "compare " + store + " '" + dir + "/all.fgm' --json", &out), 0) << out;
  EXPECT_NE(out.find("\"agreement_in_either\":1.0"), std::string::npos) << out;
}

INSTANTIATE_TEST_SUITE_P(Stores, StoreCrash,
                         ::testing::Values(PageStoreKind::kSqlite, PageStoreKind::kLmdb),
                         [](const auto& info) {
                           return info.param == PageStoreKind::kLmdb ? "Lmdb" : "Sqlite";
                         });

}  // namespace
}  // namespace fragg::test
