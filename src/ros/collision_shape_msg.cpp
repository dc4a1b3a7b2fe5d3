// ~check_collision shapes: type + dimensions, or a shape_msgs/Mesh.
#include "fragg_map/ros/collision_shape_msg.h"

#include <cmath>

#include "fragg_map/errors.h"

namespace fragg::ros {
namespace {

void requireCount(const std::string& type, const std::vector<double>& d, size_t n,
                  const char* what) {
  if (d.size() != n)
    throw fragg::InvalidArgument(type + " needs " + std::to_string(n) + " dimensions (" + what +
                                 "), got " + std::to_string(d.size()));
}

}  // namespace

planning::CollisionShape shapeFromDimensions(const std::string& type,
                                             const std::vector<double>& d) {
  try {
    if (type == "box") {
      requireCount(type, d, 3, "full lengths LX LY LZ in metres");
      return planning::CollisionShape::box(0.5 * Eigen::Vector3d(d[0], d[1], d[2]));
    }
    if (type == "sphere") {
      requireCount(type, d, 1, "radius R in metres");
      return planning::CollisionShape::sphere(d[0]);
    }
    if (type == "capsule") {
      requireCount(type, d, 2, "radius R and axis length L in metres");
      return planning::CollisionShape::capsule(d[0], d[1]);
    }
  } catch (const fragg::InvalidArgument& e) {
    throw fragg::InvalidArgument("shape " + type + ": " + e.what());
  }
  throw fragg::InvalidArgument("unknown shape '" + type + "': use box, sphere, capsule or mesh");
}

geometry::TriangleMesh meshFromMsg(const shape_msgs::Mesh& msg) {
  geometry::TriangleMesh mesh;
  if (msg.triangles.empty()) return mesh;
  mesh.vertices_m.reserve(msg.vertices.size());
  for (const geometry_msgs::Point& p : msg.vertices) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw fragg::InvalidArgument("mesh: a vertex is not finite");
    mesh.vertices_m.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y),
                                 static_cast<float>(p.z));
  }
  mesh.triangles.reserve(msg.triangles.size());
  for (size_t t = 0; t < msg.triangles.size(); ++t) {
    const auto& idx = msg.triangles[t].vertex_indices;
    for (uint32_t i : idx)
      if (i >= msg.vertices.size())
        throw fragg::InvalidArgument("mesh: triangle " + std::to_string(t) + " names vertex " +
                                     std::to_string(i) + " of " +
                                     std::to_string(msg.vertices.size()));
    mesh.triangles.emplace_back(static_cast<int>(idx[0]), static_cast<int>(idx[1]),
                                static_cast<int>(idx[2]));
    mesh.solid_of_triangle.push_back(0);
  }
  mesh.solid_count = 1;
  return mesh;
}

planning::CollisionShape shapeFromRequest(
    const std::string& type, const std::vector<double>& dimensions_m, const shape_msgs::Mesh& mesh,
    const std::optional<planning::CollisionShape>& configured_mesh) {
  if (type != "mesh") return shapeFromDimensions(type, dimensions_m);
  if (!dimensions_m.empty())
    throw fragg::InvalidArgument("shape mesh takes no dimensions (got " +
                                 std::to_string(dimensions_m.size()) + ")");
  if (!mesh.triangles.empty()) {
    try {
      return planning::CollisionShape::mesh(meshFromMsg(mesh));
    } catch (const fragg::InvalidArgument& e) {
      const std::string what = e.what();
      throw fragg::InvalidArgument(what.rfind("mesh:", 0) == 0 ? what : "mesh: " + what);
    }
  }
  if (!configured_mesh)
    throw fragg::InvalidArgument(
        "shape mesh: the request has no triangles and the collision/mesh parameter is not set");
  return *configured_mesh;
}

}  // namespace fragg::ros
