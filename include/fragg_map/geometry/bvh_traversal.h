// Ray traversal of a MeshBvh's flat arrays (FRAGG_HD): the inside test by ray parity, shared by
// MeshBvh::inside on the host and the CUDA collision kernels, so both decide "inside" alike.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/geometry/triangle_queries.h"
#include "fragg_map/hd.h"

namespace fragg::geometry {

constexpr int kBvhStackSize = 96;  ///< SAH depth <= 48 plus median splits: log2(n) more
constexpr int kMaxInsideSolids = 32;

/// Slab test; the entry distance, or INFINITY when the box is missed within [0, t_max].
FRAGG_HD float bvhBoxEntry(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                           const Eigen::Vector3f& origin, const Eigen::Vector3f& inv_dir,
                           float t_max) {
  float t0 = 0.f, t1 = t_max;
  for (int a = 0; a < 3; ++a) {
    float near = (lo[a] - origin[a]) * inv_dir[a];
    float far = (hi[a] - origin[a]) * inv_dir[a];
    if (near > far) {
      const float tmp = near;
      near = far;
      far = tmp;
    }
    if (near != near) near = -INFINITY;  // NaN (0 * inf): origin on the slab plane
    if (far != far) far = INFINITY;
    t0 = t0 < near ? near : t0;
    t1 = far < t1 ? far : t1;
    if (t0 > t1) return INFINITY;
  }
  return t0;
}

/// Whether p is inside one of the solids: parity of the crossings of the ray p + t dir (t > 0)
/// per solid, exact barycentric limits. solid_of_slot[i]: the solid of leaf triangle i.
/// Sets *overflow (and answers false) when more than kMaxInsideSolids solids lie on the ray.
FRAGG_HD bool bvhInside(const MeshBvh::Node* nodes, const MeshBvh::Tri* tris,
                        const int32_t* solid_of_slot, const Eigen::Vector3f& p,
                        const Eigen::Vector3f& dir, bool* overflow) {
  const Eigen::Vector3f inv_dir(1.f / dir[0], 1.f / dir[1], 1.f / dir[2]);
  int32_t solids[kMaxInsideSolids];
  uint32_t parity = 0;
  int n = 0;
  uint32_t stack[kBvhStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const uint32_t index = stack[--top];
    const MeshBvh::Node& node = nodes[index];
    if (bvhBoxEntry(node.lo, node.hi, p, inv_dir, INFINITY) == INFINITY) continue;
    if (node.count == 0) {
      stack[top++] = node.first;
      stack[top++] = index + 1;
      continue;
    }
    for (uint32_t i = node.first; i < node.first + node.count; ++i) {
      const float t = rayTriangle(p, dir, tris[i].v0, tris[i].e1, tris[i].e2, 0.f);
      if (!(t > 0.f && t < INFINITY)) continue;
      const int32_t s = solid_of_slot[i];
      int k = 0;
      while (k < n && solids[k] != s) ++k;
      if (k == n) {
        if (n == kMaxInsideSolids) {
          *overflow = true;
          return false;
        }
        solids[n++] = s;
      }
      parity ^= 1u << k;
    }
  }
  return parity != 0;
}

}  // namespace fragg::geometry
