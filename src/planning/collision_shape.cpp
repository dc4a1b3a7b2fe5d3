#include "fragg_map/planning/collision_shape.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>

#include "fragg_map/errors.h"

namespace fragg::planning {

namespace {
void requirePositive(double v, const char* what) {
  if (!std::isfinite(v) || v <= 0.0)
    throw InvalidArgument(fmt::format("{} must be finite and > 0, got {}", what, v));
}

// Closed: within each solid, every undirected edge (vertices compared by position, so that
// files repeating a vertex per face still close) is used by exactly two triangles.
bool everyEdgeSharedTwice(const geometry::TriangleMesh& mesh) {
  using Point = std::array<float, 3>;
  std::map<std::tuple<int32_t, Point, Point>, int> uses;
  for (size_t t = 0; t < mesh.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f& va = mesh.vertices_m[tri[k]];
      const Eigen::Vector3f& vb = mesh.vertices_m[tri[(k + 1) % 3]];
      Point a{va.x(), va.y(), va.z()}, b{vb.x(), vb.y(), vb.z()};
      if (b < a) std::swap(a, b);
      ++uses[{mesh.solid_of_triangle[t], a, b}];
    }
  }
  for (const auto& [edge, n] : uses)
    if (n != 2) return false;
  return true;
}
}  // namespace

CollisionShape CollisionShape::box(const Eigen::Vector3d& half_extents_m) {
  for (int i = 0; i < 3; ++i) requirePositive(half_extents_m[i], "box half extent");
  CollisionShape s;
  s.kind_ = ShapeKind::kBox;
  s.half_extents_m_ = half_extents_m;
  s.bounding_radius_m_ = half_extents_m.norm();
  return s;
}

CollisionShape CollisionShape::sphere(double radius_m) {
  requirePositive(radius_m, "sphere radius");
  CollisionShape s;
  s.kind_ = ShapeKind::kSphere;
  s.radius_m_ = radius_m;
  s.bounding_radius_m_ = radius_m;
  return s;
}

CollisionShape CollisionShape::capsule(double radius_m, double length_m) {
  requirePositive(radius_m, "capsule radius");
  if (!std::isfinite(length_m) || length_m < 0.0)
    throw InvalidArgument(fmt::format("capsule length must be finite and >= 0, got {}", length_m));
  CollisionShape s;
  s.kind_ = ShapeKind::kCapsule;
  s.radius_m_ = radius_m;
  s.length_m_ = length_m;
  s.bounding_radius_m_ = radius_m + 0.5 * length_m;
  return s;
}

CollisionShape CollisionShape::mesh(const geometry::TriangleMesh& mesh, double scale) {
  requirePositive(scale, "mesh scale");
  if (mesh.empty()) throw InvalidArgument("the mesh has no triangles");
  if (mesh.solid_of_triangle.size() != mesh.size())
    throw InvalidArgument("the mesh's solid ids do not match its triangles");
  geometry::TriangleMesh scaled = mesh;
  double radius = 0.0;
  for (Eigen::Vector3f& v : scaled.vertices_m) {
    const Eigen::Vector3d p = v.cast<double>() * scale;
    if (!p.allFinite()) throw InvalidArgument("the mesh has a non-finite vertex");
    v = p.cast<float>();
    radius = std::max(radius, p.norm());
  }
  double area_m2 = 0.0;
  for (const Eigen::Vector3i& t : scaled.triangles) {
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || static_cast<size_t>(t[k]) >= scaled.vertices_m.size())
        throw InvalidArgument("the mesh has a triangle with a vertex index out of range");
    const Eigen::Vector3d a = scaled.vertices_m[t[0]].cast<double>();
    const Eigen::Vector3d b = scaled.vertices_m[t[1]].cast<double>();
    const Eigen::Vector3d c = scaled.vertices_m[t[2]].cast<double>();
    area_m2 += 0.5 * (b - a).cross(c - a).norm();
  }
  if (!(area_m2 > 1e-12))
    throw InvalidArgument("the mesh is degenerate: its triangles have no area");
  CollisionShape s;
  s.kind_ = ShapeKind::kMesh;
  s.mesh_closed_ = everyEdgeSharedTwice(scaled);
  s.bounding_radius_m_ = radius;
  s.bvh_ = std::make_shared<const geometry::MeshBvh>(std::move(scaled));
  return s;
}

std::string CollisionShape::describe() const {
  switch (kind_) {
    case ShapeKind::kBox:
      return fmt::format("box {} x {} x {} m", 2 * half_extents_m_.x(), 2 * half_extents_m_.y(),
                         2 * half_extents_m_.z());
    case ShapeKind::kSphere:
      return fmt::format("sphere r {} m", radius_m_);
    case ShapeKind::kCapsule:
      return fmt::format("capsule r {} m, length {} m", radius_m_, length_m_);
    case ShapeKind::kMesh:
      return fmt::format("mesh of {} triangles ({})", bvh_->mesh().size(),
                         mesh_closed_ ? "closed" : "open: surface only");
  }
  return "shape";
}

}  // namespace fragg::planning
