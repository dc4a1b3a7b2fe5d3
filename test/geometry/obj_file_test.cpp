// Wavefront OBJ files: round trip (bit-exact vertices, solids grouped), the reader's accepted
// face forms and its errors (naming the file and the line).
#include "fragg_map/geometry/obj_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <map>

#include "fragg_map/errors.h"
#include "mesh_test_util.h"

namespace fragg::geometry {
namespace {

void writeText(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
}

TEST(GeometryObjFile, RoundTripKeepsVerticesTrianglesAndSolids) {
  TriangleMesh m;
  m.appendSolid(test::boxSolid({-1.25f, 0.1f, 0}, {3.3f, 2.7f, 1.9f}));
  m.append(test::randomSoup(50, 100.f, 3.f, 5));  // coordinates with every digit used
  m.appendSolid(test::boxSolid({1e-3f, -7.77f, 1e4f}, {0.5f, 1.f / 3.f, 1.00001e4f}));
  const std::string path = test::testDir() + "/m.obj";
  writeObj(m, path);
  const TriangleMesh r = readObj(path);
  ASSERT_EQ(r.solid_count, 3);
  ASSERT_EQ(r.triangles.size(), m.triangles.size());
  // Faces are written grouped by solid; here solids are already contiguous, so order is kept.
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    EXPECT_EQ(r.solid_of_triangle[i], m.solid_of_triangle[i]);
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(r.vertices_m[r.triangles[i][k]], m.vertices_m[m.triangles[i][k]]);  // bit-exact
  }
}

TEST(GeometryObjFile, TrianglesOfInterleavedSolidsAreWrittenGroupedBySolid) {
  TriangleMesh m;
  m.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1);
  m.addTriangle({0, 0, 1}, {1, 0, 1}, {0, 1, 1}, 0);
  m.addTriangle({0, 0, 2}, {1, 0, 2}, {0, 1, 2}, 1);
  const std::string path = test::testDir() + "/m.obj";
  writeObj(m, path);
  const TriangleMesh r = readObj(path);
  ASSERT_EQ(r.solid_count, 2);
  ASSERT_EQ(r.size(), 3u);
  // Solid 0 first (the triangle at z = 1), then solid 1 in its own order (z = 0, z = 2).
  EXPECT_EQ(r.solid_of_triangle, (std::vector<int32_t>{0, 1, 1}));
  EXPECT_EQ(r.vertices_m[r.triangles[0][0]].z(), 1.f);
  EXPECT_EQ(r.vertices_m[r.triangles[1][0]].z(), 0.f);
  EXPECT_EQ(r.vertices_m[r.triangles[2][0]].z(), 2.f);
}

TEST(GeometryObjFile, ReaderAcceptsFaceFormsAndStartsASolidPerObjectOrGroup) {
  const std::string dir = test::testDir();
  writeText(dir + "/quad.obj",
            "# comment\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n"
            "f 1 2 3\n"                   // before any o/g: a solid of its own
            "g a\nf 1/1 2/2/2 3//3 -1\n"  // a quad, fanned; the last index is relative
            "o b\nf -4 -3 -2\n");
  const TriangleMesh q = readObj(dir + "/quad.obj");
  ASSERT_EQ(q.size(), 4u);
  EXPECT_EQ(q.solid_count, 3);
  EXPECT_EQ(q.solid_of_triangle, (std::vector<int32_t>{0, 1, 1, 2}));
  EXPECT_EQ(q.triangles[1], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(q.triangles[2], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(q.triangles[3], Eigen::Vector3i(0, 1, 2));
}

TEST(GeometryObjFile, ReaderErrorsNameTheFileAndTheLine) {
  const std::string dir = test::testDir();
  const std::map<std::string, std::string> bad = {
      {"undefined_vertex", "v 0 0 0\nv 1 0 0\nf 1 2 3\n"},
      {"zero_index", "v 0 0 0\nv 1 0 0\nf 0 1 2\n"},
      {"short_vertex", "v 0 0 0\nv 1 0\nf 1 2 1\n"},
      {"two_corners", "v 0 0 0\nv 1 0 0\nf 1 2\n"},
      {"not_a_number", "v 0 0 0\nv 1 0 0\nf 1 2 x\n"},
  };
  for (const auto& [name, text] : bad) {
    const std::string path = dir + "/" + name + ".obj";
    writeText(path, text);
    try {
      readObj(path);
      ADD_FAILURE() << name << ": no error";
    } catch (const IoError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      const std::string line = name == "short_vertex" ? "line 2" : "line 3";
      EXPECT_NE(what.find(line), std::string::npos) << what;
    }
  }
  writeText(dir + "/no_faces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  EXPECT_THROW(readObj(dir + "/no_faces.obj"), IoError);
  EXPECT_THROW(readObj(dir + "/missing.obj"), IoError);
  EXPECT_THROW(writeObj(test::boxSolid({0, 0, 0}, {1, 1, 1}), dir + "/no/such/dir/m.obj"), IoError);
}

}  // namespace
}  // namespace fragg::geometry
