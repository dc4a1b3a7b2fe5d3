#include "fragg_map/geometry/mesh_primitives.h"

#include <cmath>

#include "fragg_map/errors.h"

namespace fragg::geometry {

TriangleMesh ellipsoidMesh(const Eigen::Vector3f& semi_axes_m, int rings, int segments) {
  if (rings < 2 || segments < 3 || !(semi_axes_m.minCoeff() > 0.f) || !semi_axes_m.allFinite())
    throw InvalidArgument("ellipsoid: needs rings >= 2, segments >= 3 and semi-axes > 0");
  TriangleMesh m;
  const Eigen::Vector3d a = semi_axes_m.cast<double>();
  m.vertices_m.push_back(Eigen::Vector3f(0.f, 0.f, semi_axes_m.z()));
  for (int i = 1; i < rings; ++i) {
    const double theta = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2.0 * M_PI * j / segments;
      m.vertices_m.push_back(Eigen::Vector3d(a.x() * std::sin(theta) * std::cos(phi),
                                             a.y() * std::sin(theta) * std::sin(phi),
                                             a.z() * std::cos(theta))
                                 .cast<float>());
    }
  }
  m.vertices_m.push_back(Eigen::Vector3f(0.f, 0.f, -semi_axes_m.z()));
  const int south = static_cast<int>(m.vertices_m.size()) - 1;
  const auto ring = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
  // Counter-clockwise seen from outside.
  for (int j = 0; j < segments; ++j) {
    m.triangles.emplace_back(0, ring(1, j), ring(1, j + 1));
    m.triangles.emplace_back(south, ring(rings - 1, j + 1), ring(rings - 1, j));
    for (int i = 1; i + 1 < rings; ++i) {
      m.triangles.emplace_back(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
      m.triangles.emplace_back(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
    }
  }
  m.solid_of_triangle.assign(m.triangles.size(), 0);
  m.solid_count = 1;
  return m;
}

}  // namespace fragg::geometry
