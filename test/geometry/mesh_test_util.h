// Hand-built meshes and temporary folders for the geometry tests (no simulator primitives:
// fragg_map_geometry is tested on its own).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cstdlib>
#include <random>
#include <string>

#include "fragg_map/geometry/triangle_mesh.h"
#include "test_dir.h"

namespace fragg::geometry::test {

/// The closed axis-aligned box [lo, hi] as one solid: 8 vertices, 12 triangles facing out.
inline TriangleMesh boxSolid(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices_m.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                              (i & 4) ? hi.z() : lo.z());
  // Corner i has x from bit 0, y from bit 1, z from bit 2. Each face: a quad counter-clockwise
  // seen from outside, split along its first diagonal.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.emplace_back(q[0], q[1], q[2]);
    m.triangles.emplace_back(q[0], q[2], q[3]);
  }
  m.solid_of_triangle.assign(m.triangles.size(), 0);
  m.solid_count = 1;
  return m;
}

/// `count` small random triangles (edges up to `size_m`) in the cube [-half_m, half_m]^3, all in
/// solid 0 (a triangle soup: fine for ray hits and distances, not for "inside").
inline TriangleMesh randomSoup(int count, float half_m, float size_m, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-half_m, half_m), off(-size_m, size_m);
  TriangleMesh m;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3f a(pos(rng), pos(rng), pos(rng));
    m.addTriangle(a, a + Eigen::Vector3f(off(rng), off(rng), off(rng)),
                  a + Eigen::Vector3f(off(rng), off(rng), off(rng)), 0);
  }
  return m;
}

using fragg::test::testDir;

}  // namespace fragg::geometry::test
