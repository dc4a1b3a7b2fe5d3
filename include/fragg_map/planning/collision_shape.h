// The shapes a collision check moves through the map: oriented box, sphere, capsule and
// triangle mesh. Each is defined in its own frame (the shape frame, metres); a check places it
// with T_map_shape, the shape's centre (box, sphere, capsule) or mesh origin in the map frame.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/geometry/triangle_mesh.h"

namespace fragg::planning {

enum class ShapeKind { kBox, kSphere, kCapsule, kMesh };

class CollisionShape {
 public:
  /// Box centred on the shape origin, axes along the shape frame's, half extents in metres.
  static CollisionShape box(const Eigen::Vector3d& half_extents_m);
  static CollisionShape sphere(double radius_m);
  /// Cylinder of `length_m` along the shape's z axis, centred on the origin, with hemispherical
  /// caps of `radius_m` (total extent along z: length_m + 2 radius_m). length_m may be 0.
  static CollisionShape capsule(double radius_m, double length_m);
  /// Triangle mesh (shape frame, metres) scaled by `scale` about the origin. Throws
  /// InvalidArgument for an empty or degenerate mesh (no triangle of positive area, or a
  /// non-finite vertex) or a scale that is not finite and > 0. Whether the mesh is closed
  /// (every edge shared by exactly two triangles of its solid) decides whether cells inside it
  /// count (meshClosed()).
  static CollisionShape mesh(const geometry::TriangleMesh& mesh, double scale = 1.0);

  ShapeKind kind() const { return kind_; }
  const Eigen::Vector3d& halfExtents() const { return half_extents_m_; }  ///< box
  double radius() const { return radius_m_; }                             ///< sphere, capsule
  double length() const { return length_m_; }                             ///< capsule
  /// Mesh in the shape frame (scaled), its BVH; nullptr for the other shapes.
  const geometry::MeshBvh* meshBvh() const { return bvh_.get(); }
  bool meshClosed() const { return mesh_closed_; }
  /// Radius of a sphere about the shape origin that holds the whole shape (metres).
  double boundingRadius() const { return bounding_radius_m_; }
  std::string describe() const;

 private:
  CollisionShape() = default;
  ShapeKind kind_ = ShapeKind::kSphere;
  Eigen::Vector3d half_extents_m_ = Eigen::Vector3d::Zero();
  double radius_m_ = 0.0, length_m_ = 0.0, bounding_radius_m_ = 0.0;
  std::shared_ptr<const geometry::MeshBvh> bvh_;
  bool mesh_closed_ = false;
};

}  // namespace fragg::planning
