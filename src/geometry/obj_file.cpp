#include "fragg_map/geometry/obj_file.h"

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"

namespace fragg::geometry {

void writeObj(const TriangleMesh& mesh, const std::string& path) {
  AtomicFile out(path);
  out.write(fmt::format("# fragg_map mesh: {} vertices, {} triangles, {} closed solids\n",
                        mesh.vertices_m.size(), mesh.triangles.size(), mesh.solid_count));
  std::string buf;
  for (const Eigen::Vector3f& v : mesh.vertices_m)
    buf += fmt::format("v {} {} {}\n", v.x(), v.y(), v.z());
  out.write(buf);
  // Triangles grouped by solid, in solid order (stable within a solid).
  std::vector<std::vector<size_t>> by_solid(mesh.solid_count);
  for (size_t i = 0; i < mesh.triangles.size(); ++i)
    by_solid.at(mesh.solid_of_triangle[i]).push_back(i);
  for (int32_t s = 0; s < mesh.solid_count; ++s) {
    buf = fmt::format("o solid_{}\n", s);
    for (size_t i : by_solid[s]) {
      const Eigen::Vector3i& t = mesh.triangles[i];
      buf += fmt::format("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    out.write(buf);
  }
  out.commit();
}

namespace {

[[noreturn]] void fail(const std::string& path, size_t line, const std::string& what) {
  throw IoError(fmt::format("{}: line {}: {}", path, line, what));
}

}  // namespace

TriangleMesh readObj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path + ": cannot open OBJ file");
  TriangleMesh mesh;
  int32_t solid = -1;
  std::string line;
  size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream ss(line);
    std::string tag;
    if (!(ss >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      double x, y, z;
      if (!(ss >> x >> y >> z)) fail(path, number, "a vertex needs three numbers");
      mesh.vertices_m.emplace_back(float(x), float(y), float(z));
    } else if (tag == "o" || tag == "g") {
      solid = mesh.solid_count++;
    } else if (tag == "f") {
      std::vector<int32_t> idx;
      std::string item;
      while (ss >> item) {
        char* end = nullptr;
        const long v = std::strtol(item.c_str(), &end, 10);
        if (end == item.c_str() || v == 0) fail(path, number, "bad face index '" + item + "'");
        const long n = static_cast<long>(mesh.vertices_m.size());
        const long zero_based = v > 0 ? v - 1 : n + v;
        if (zero_based < 0 || zero_based >= n)
          fail(path, number, "face index " + item + " refers to a vertex not defined before");
        idx.push_back(static_cast<int32_t>(zero_based));
      }
      if (idx.size() < 3) fail(path, number, "a face needs at least three vertices");
      if (solid < 0) solid = mesh.solid_count++;
      for (size_t k = 1; k + 1 < idx.size(); ++k) {
        mesh.triangles.emplace_back(idx[0], idx[k], idx[k + 1]);
        mesh.solid_of_triangle.push_back(solid);
      }
    }
  }
  if (in.bad()) throw IoError(path + ": read error");
  if (mesh.triangles.empty()) throw IoError(path + ": OBJ file without faces");
  return mesh;
}

}  // namespace fragg::geometry
