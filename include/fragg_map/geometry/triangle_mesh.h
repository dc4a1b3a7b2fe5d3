// A triangle mesh made of closed solids: every triangle belongs to one solid (a box, a tree
// trunk, a ground slab...), so that "inside" can be decided per solid by ray parity even
// where solids overlap. Coordinates in metres, in the frame of whoever built the mesh (the
// map frame for the simulator's scenes).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace fragg::geometry {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices_m;
  std::vector<Eigen::Vector3i> triangles;  ///< vertex indices, counter-clockwise seen from outside
  std::vector<int32_t> solid_of_triangle;  ///< one entry per triangle
  int32_t solid_count = 0;

  size_t size() const { return triangles.size(); }
  bool empty() const { return triangles.empty(); }

  /// Appends `other` (its solids keep their grouping and get new ids after ours).
  void append(const TriangleMesh& other);
  /// Appends `solid` as one new solid, whatever the solid ids it carries.
  void appendSolid(const TriangleMesh& solid);
  /// Adds a triangle to solid `solid` (vertices appended).
  void addTriangle(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c,
                   int32_t solid);
};

}  // namespace fragg::geometry
