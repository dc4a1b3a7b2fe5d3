// A bounding volume hierarchy over a triangle mesh: nearest ray hit, "is a point within r of
// the surface", distance to the surface and "is a point inside a solid". Generic queries: the
// simulator's sensors cast rays with them, map evaluation and collision checks ask the others.
// Immutable after construction; every query is thread-safe.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "fragg_map/geometry/triangle_mesh.h"
#include "fragg_map/geometry/triangle_queries.h"

namespace fragg::geometry {

struct RayHit {
  float t_m = 0.f;        ///< distance along the (unit) ray direction
  int32_t triangle = -1;  ///< index into the mesh's triangles
};

class MeshBvh {
 public:
  /// Builds the hierarchy (binned surface area heuristic, <= 4 triangles a leaf).
  explicit MeshBvh(TriangleMesh mesh);

  const TriangleMesh& mesh() const { return mesh_; }
  Eigen::AlignedBox3f bounds() const;

  /// Nearest hit with 0 < t < t_max_m along origin + t * dir_unit; false when none.
  bool intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir_unit, float t_max_m,
                 RayHit* hit) const;

  /// Whether some triangle is within distance r_m of p (stops at the first one found).
  bool withinDistance(const Eigen::Vector3f& p, float r_m) const;

  /// Distance from p to the surface, or max_m when the surface is farther than that.
  float distance(const Eigen::Vector3f& p, float max_m) const;

  /// Whether p is inside one of the mesh's closed solids: ray parity per solid, along a fixed
  /// direction that no axis-aligned edge or face is parallel to (at most 32 solids may lie
  /// above p: more throws InvalidArgument).
  bool inside(const Eigen::Vector3f& p) const;

  struct Node {
    Eigen::Vector3f lo, hi;
    uint32_t first = 0;  ///< leaf: first triangle (in order_); inner: right child
    uint32_t count = 0;  ///< leaf: triangle count; inner: 0 (left child is the next node)
  };
  struct Tri {
    Eigen::Vector3f v0, e1, e2;
  };
  /// The flat hierarchy (node 0 the root), for device copies (geometry/bvh_traversal.h).
  const std::vector<Node>& nodes() const { return nodes_; }
  const std::vector<Tri>& leafTriangles() const { return tris_; }            ///< in leaf order
  const std::vector<uint32_t>& leafOrder() const { return order_; }          ///< triangle of a slot
  const std::vector<int32_t>& leafSolids() const { return solid_of_slot_; }  ///< solid of a slot
  /// The direction of inside()'s parity rays: an irrational-looking direction, steep upwards
  /// (few solids lie above a point, and no axis-aligned face or edge of buildings, boxes or
  /// slabs is parallel to it). Inline: the CUDA collision code in the core's CUDA object
  /// library uses it, and the core does not link the geometry library.
  static Eigen::Vector3f insideRayDirection() {
    return Eigen::Vector3f(0.0917f, 0.0531f, 1.0f).normalized();
  }

 private:
  uint32_t build(uint32_t begin, uint32_t end, const std::vector<Eigen::Vector3f>& centroids,
                 const std::vector<Eigen::AlignedBox3f>& boxes, int depth);
  template <typename Visit>
  void traverseRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t_max,
                   float edge_eps, Visit&& visit) const;

  TriangleMesh mesh_;
  std::vector<Node> nodes_;
  std::vector<uint32_t> order_;         ///< triangle index of each leaf slot
  std::vector<Tri> tris_;               ///< in leaf order
  std::vector<int32_t> solid_of_slot_;  ///< in leaf order
};

}  // namespace fragg::geometry
