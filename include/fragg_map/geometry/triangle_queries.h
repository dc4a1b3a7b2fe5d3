// Queries on one triangle: ray intersection, point distance, overlap with an axis-aligned box.
// The mesh BVH runs the first two over its leaves; map evaluation (and, later, collision
// checking) asks the third per voxel.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "fragg_map/hd.h"

namespace fragg::geometry {

/// Squared distance from p to the triangle (a, b, c).
inline float pointTriangleDistanceSq(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                     const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  // Closest point by Voronoi region (Ericson, Real-Time Collision Detection, 5.1.5).
  const Eigen::Vector3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.f && d2 <= 0.f) return ap.squaredNorm();
  const Eigen::Vector3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.f && d4 <= d3) return bp.squaredNorm();
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.f && d1 >= 0.f && d3 <= 0.f) return (ap - ab * (d1 / (d1 - d3))).squaredNorm();
  const Eigen::Vector3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.f && d5 <= d6) return cp.squaredNorm();
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.f && d2 >= 0.f && d6 <= 0.f) return (ap - ac * (d2 / (d2 - d6))).squaredNorm();
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.f && (d4 - d3) >= 0.f && (d5 - d6) >= 0.f) {
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (bp - (c - b) * w).squaredNorm();
  }
  const float denom = 1.f / (va + vb + vc);
  const float v = vb * denom, w = vc * denom;
  return (ap - ab * v - ac * w).squaredNorm();
}

/// Möller-Trumbore: distance t along dir to the triangle (v0, v0 + e1, v0 + e2), or a negative
/// value when the line misses it. Barycentric limits are widened by edge_eps. FRAGG_HD: the CUDA
/// collision kernels' inside test runs it too.
FRAGG_HD float rayTriangle(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir,
                           const Eigen::Vector3f& v0, const Eigen::Vector3f& e1,
                           const Eigen::Vector3f& e2, float edge_eps = 0.f) {
  const Eigen::Vector3f pv = dir.cross(e2);
  const float det = e1.dot(pv);
  if (fabsf(det) < 1e-12f) return -1.f;
  const float inv = 1.f / det;
  const Eigen::Vector3f tv = origin - v0;
  const float u = tv.dot(pv) * inv;
  if (u < -edge_eps || u > 1.f + edge_eps) return -1.f;
  const Eigen::Vector3f qv = tv.cross(e1);
  const float v = dir.dot(qv) * inv;
  if (v < -edge_eps || u + v > 1.f + edge_eps) return -1.f;
  return e2.dot(qv) * inv;
}

/// Whether the triangle (a, b, c) meets the axis-aligned box centre +- half (separating axis
/// test of Akenine-Moller); touching counts.
inline bool triangleBoxOverlap(const Eigen::Vector3d& centre, const Eigen::Vector3d& half,
                               const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c) {
  const Eigen::Vector3d v[3] = {a - centre, b - centre, c - centre};
  // Box face normals.
  for (int i = 0; i < 3; ++i) {
    const double lo = std::min({v[0][i], v[1][i], v[2][i]});
    const double hi = std::max({v[0][i], v[1][i], v[2][i]});
    if (lo > half[i] || hi < -half[i]) return false;
  }
  const Eigen::Vector3d e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  // Triangle plane.
  const Eigen::Vector3d n = e[0].cross(e[1]);
  if (std::abs(n.dot(v[0])) > half.dot(n.cwiseAbs())) return false;
  // Cross products of the box axes with the triangle edges.
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d axis = Eigen::Vector3d::Unit(i).cross(e[j]);
      const double p0 = axis.dot(v[0]), p1 = axis.dot(v[1]), p2 = axis.dot(v[2]);
      const double r = half.dot(axis.cwiseAbs());
      if (std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r) return false;
    }
  return true;
}

}  // namespace fragg::geometry
