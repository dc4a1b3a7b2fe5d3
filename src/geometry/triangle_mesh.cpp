#include "fragg_map/geometry/triangle_mesh.h"

namespace fragg::geometry {

void TriangleMesh::append(const TriangleMesh& other) {
  const int32_t offset = static_cast<int32_t>(vertices_m.size());
  vertices_m.insert(vertices_m.end(), other.vertices_m.begin(), other.vertices_m.end());
  for (const Eigen::Vector3i& t : other.triangles)
    triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  for (int32_t s : other.solid_of_triangle) solid_of_triangle.push_back(s + solid_count);
  solid_count += other.solid_count;
}

void TriangleMesh::appendSolid(const TriangleMesh& solid) {
  const int32_t offset = static_cast<int32_t>(vertices_m.size());
  vertices_m.insert(vertices_m.end(), solid.vertices_m.begin(), solid.vertices_m.end());
  for (const Eigen::Vector3i& t : solid.triangles) {
    triangles.push_back(t + Eigen::Vector3i::Constant(offset));
    solid_of_triangle.push_back(solid_count);
  }
  ++solid_count;
}

void TriangleMesh::addTriangle(const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                               const Eigen::Vector3f& c, int32_t solid) {
  const int32_t i = static_cast<int32_t>(vertices_m.size());
  vertices_m.push_back(a);
  vertices_m.push_back(b);
  vertices_m.push_back(c);
  triangles.emplace_back(i, i + 1, i + 2);
  solid_of_triangle.push_back(solid);
  if (solid >= solid_count) solid_count = solid + 1;
}

}  // namespace fragg::geometry
