// scripts/install_deps.sh waits for a held apt/dpkg lock instead of failing: its lock wait
// (sourced, so nothing is installed) against a file this test locks the way apt does (fcntl),
// released while the script waits, or held past its time limit.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <future>
#include <iterator>
#include <string>
#include <thread>

#include "test_dir.h"

namespace fragg {
namespace {

struct Result {
  int exit_code = -1;
  std::string out;
  double seconds = 0;
};

// Runs wait_for_apt_lock from the sourced script with FRAGG_APT_LOCK_FILES = lock_files.
Result waitForLock(const std::string& dir, const std::string& lock_files, int limit_s) {
  const std::string out = dir + "/out.txt";
  const std::string cmd = "FRAGG_APT_LOCK_FILES='" + lock_files +
                          "' FRAGG_APT_LOCK_WAIT_S=" + std::to_string(limit_s) +
                          " FRAGG_APT_LOCK_POLL_S=0.2 bash -c 'source \"" FRAGG_INSTALL_DEPS
                          "\" && wait_for_apt_lock' > '" +
                          out + "' 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  Result r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(out);
  r.out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return r;
}

// A whole-file write lock, as apt and dpkg take on their lock files (fcntl F_SETLK).
int lockFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT, 0644);
  EXPECT_GE(fd, 0) << path;
  struct flock lock {};
  lock.l_type = F_WRLCK;
  lock.l_whence = SEEK_SET;
  EXPECT_EQ(::fcntl(fd, F_SETLK, &lock), 0);
  return fd;
}

size_t count(const std::string& text, const std::string& word) {
  size_t n = 0;
  for (size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) ++n;
  return n;
}

TEST(InstallDeps, WaitsForAHeldLockThenProceeds) {
  const std::string dir = test::testDir();
  const std::string lock = dir + "/lock-frontend", other = dir + "/lists-lock";
  std::ofstream(other).put('\n');
  const int fd = lockFile(lock);
  // Released 2 s after the script starts waiting.
  auto waited =
      std::async(std::launch::async, [&] { return waitForLock(dir, other + " " + lock, 60); });
  std::this_thread::sleep_for(std::chrono::seconds(2));
  ::close(fd);
  const Result r = waited.get();
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_GE(r.seconds, 1.8);
  EXPECT_LT(r.seconds, 30.0);
  EXPECT_EQ(count(r.out, "holds its lock; waiting for it (at most 60 s)"), 1u) << r.out;
  EXPECT_EQ(count(r.out, "the lock is free after"), 1u) << r.out;
}

TEST(InstallDeps, GivesUpWhenTheLockStaysHeldAndIgnoresOtherLocks) {
  const std::string dir = test::testDir();
  const std::string lock = dir + "/lock", unrelated = dir + "/unrelated";
  std::ofstream(lock).put('\n');
  const int fd = lockFile(unrelated);
  // A lock on another file (another inode) is not apt's: no wait, no output.
  Result r = waitForLock(dir, lock + " " + dir + "/missing", 60);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, "");
  EXPECT_LT(r.seconds, 5.0);
  // Held past the limit: one line saying so, exit status 1.
  r = waitForLock(dir, unrelated, 1);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(count(r.out, "waiting for it"), 1u) << r.out;
  EXPECT_EQ(count(r.out, "still held after 1 s"), 1u) << r.out;
  ::close(fd);
}

}  // namespace
}  // namespace fragg
