// A per-test scratch directory, shared by the test suites.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace fragg::test {

/// A per-test directory under FRAGG_TEST_TMP (tests may run in parallel), emptied first. The
/// environment variable FRAGG_TEST_TMP, when set, replaces the build's folder: two processes
/// running the same test at once (e.g. under two compute-sanitizer tools) each need their own.
inline std::string testDir() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const char* env_root = std::getenv("FRAGG_TEST_TMP");
  const std::string root = env_root != nullptr && *env_root != '\0' ? env_root : FRAGG_TEST_TMP;
  const std::string dir = root + "/" + info->test_suite_name() + "." + info->name();
  const std::string cmd = "rm -rf '" + dir + "' && mkdir -p '" + dir + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
  return dir;
}

}  // namespace fragg::test
