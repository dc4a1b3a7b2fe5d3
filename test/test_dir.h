// A per-test scratch directory, shared by the test suites.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace fragg::test {

/// A per-test directory under FRAGG_TEST_TMP (tests may run in parallel), emptied first.
inline std::string testDir() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string dir =
      std::string(FRAGG_TEST_TMP) + "/" + info->test_suite_name() + "." + info->name();
  const std::string cmd = "rm -rf '" + dir + "' && mkdir -p '" + dir + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
  return dir;
}

}  // namespace fragg::test
