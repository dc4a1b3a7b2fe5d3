// Small analytic scenes and temporary folders for the simulator tests.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "fragg_map/geometry/triangle_mesh.h"
#include "fragg_map/sim/primitives.h"
#include "test_dir.h"

namespace fragg::sim::test {

/// A flat ground slab, top at z = 0, over [-half, half]^2.
inline geometry::TriangleMesh flatGround(double half_m) {
  geometry::TriangleMesh m;
  m.append(makeTerrainSlab(-half_m, -half_m, half_m, half_m, half_m / 4, 1.0,
                           [](double, double) { return 0.0; }));
  return m;
}

using fragg::test::testDir;

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << path;
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

/// Runs `program args` (a shell command line) with stdout and stderr captured in `dir`.
inline RunResult run(const std::string& program, const std::string& dir, const std::string& args) {
  const std::string out = dir + "/stdout.txt", err = dir + "/stderr.txt";
  const std::string cmd = "'" + program + "' " + args + " > '" + out + "' 2> '" + err + "'";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = readBytes(out);
  r.err = readBytes(err);
  return r;
}

}  // namespace fragg::sim::test
