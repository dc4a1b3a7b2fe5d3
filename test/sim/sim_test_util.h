// Small analytic scenes and temporary folders for the simulator tests.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "fragg_map/sim/primitives.h"
#include "fragg_map/sim/triangle_mesh.h"

namespace fragg::sim::test {

/// A flat ground slab, top at z = 0, over [-half, half]^2.
inline TriangleMesh flatGround(double half_m) {
  TriangleMesh m;
  m.append(makeTerrainSlab(-half_m, -half_m, half_m, half_m, half_m / 4, 1.0,
                           [](double, double) { return 0.0; }));
  return m;
}

/// A per-test directory under FRAGG_TEST_TMP, emptied first.
inline std::string testDir() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string dir =
      std::string(FRAGG_TEST_TMP) + "/" + info->test_suite_name() + "." + info->name();
  const std::string cmd = "rm -rf '" + dir + "' && mkdir -p '" + dir + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
  return dir;
}

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << path;
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace fragg::sim::test
