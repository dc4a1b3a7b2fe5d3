// TriangleMesh: appends keep vertex references and solid groupings.
#include "fragg_map/geometry/triangle_mesh.h"

#include <gtest/gtest.h>

#include "mesh_test_util.h"

namespace fragg::geometry {
namespace {

// The corner positions of triangle i, so that meshes can be compared whatever their indices.
std::array<Eigen::Vector3f, 3> corners(const TriangleMesh& m, size_t i) {
  const Eigen::Vector3i& t = m.triangles[i];
  return {m.vertices_m[t[0]], m.vertices_m[t[1]], m.vertices_m[t[2]]};
}

TEST(GeometryTriangleMesh, AppendShiftsVertexIndicesAndSolidIds) {
  TriangleMesh two;
  two.appendSolid(test::boxSolid({0, 0, 0}, {1, 1, 1}));
  two.appendSolid(test::boxSolid({2, 0, 0}, {3, 1, 1}));
  TriangleMesh m;
  m.appendSolid(test::boxSolid({-5, -5, -5}, {-4, -4, -4}));
  m.append(two);
  ASSERT_EQ(m.solid_count, 3);
  ASSERT_EQ(m.size(), 36u);
  ASSERT_EQ(m.vertices_m.size(), 24u);
  for (size_t i = 0; i < two.size(); ++i) {
    EXPECT_EQ(corners(m, 12 + i), corners(two, i));
    EXPECT_EQ(m.solid_of_triangle[12 + i], two.solid_of_triangle[i] + 1);
  }
  EXPECT_EQ(m.solid_of_triangle.front(), 0);
  EXPECT_EQ(m.solid_of_triangle.back(), 2);
}

TEST(GeometryTriangleMesh, AppendSolidMakesOneSolidWhateverTheIdsItCarries) {
  TriangleMesh two;
  two.appendSolid(test::boxSolid({0, 0, 0}, {1, 1, 1}));
  two.appendSolid(test::boxSolid({2, 0, 0}, {3, 1, 1}));
  TriangleMesh m;
  m.appendSolid(test::boxSolid({-5, -5, -5}, {-4, -4, -4}));
  m.appendSolid(two);
  EXPECT_EQ(m.solid_count, 2);
  for (size_t i = 12; i < m.size(); ++i) EXPECT_EQ(m.solid_of_triangle[i], 1);
  EXPECT_EQ(corners(m, 35), corners(two, 23));
}

TEST(GeometryTriangleMesh, AddTriangleGrowsTheSolidCount) {
  TriangleMesh m;
  EXPECT_TRUE(m.empty());
  m.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 4);
  EXPECT_EQ(m.solid_count, 5);
  m.addTriangle({0, 0, 1}, {1, 0, 1}, {0, 1, 1}, 2);  // an existing id: no growth
  EXPECT_EQ(m.solid_count, 5);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(3, 4, 5));
  EXPECT_EQ(m.vertices_m[4], Eigen::Vector3f(1, 0, 1));
  EXPECT_EQ(m.solid_of_triangle, (std::vector<int32_t>{4, 2}));
}

}  // namespace
}  // namespace fragg::geometry
