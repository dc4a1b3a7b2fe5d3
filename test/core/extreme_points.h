// The finite points of issue 39 (sensor frame, metres) that crashed or broke insertion: a huge
// coordinate with a tiny non-zero other one, denormals, the float range's ends. Shared by the
// core, gpu and server tests (test/fuzz/make_seeds.py writes the same list into the seeds).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace fragg::test {

inline const std::vector<Eigen::Vector3f>& extremePoints() {
  static const std::vector<Eigen::Vector3f> points = {
      {3.7e27f, -4e-20f, -3.7e27f}, {-3.7e27f, 4e-20f, 3.7e27f}, {4e-20f, 3.7e27f, -3.7e27f},
      {3.4e38f, 1e-30f, -3.4e38f},  {1e30f, 1e30f, 1e30f},       {1e-45f, 1e-45f, 1e-45f},
      {1e19f, -1e-38f, 1e19f},      {20.f, 1e-40f, -20.f},       {1e15f, 1e15f, -1e-25f},
      {3e38f, 3e38f, 3e38f}};
  return points;
}

}  // namespace fragg::test
