// Independent references for the collision tests: written differently from the library's
// tests (vertex projections for boxes, edge distances for capsules, half-spaces for convex
// meshes), and a brute force over every cell of a generous range.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "fragg_map/geometry/triangle_mesh.h"
#include "fragg_map/geometry/triangle_queries.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/collision_check.h"

namespace fragg::planning::test {

using Vec3 = Eigen::Vector3d;

inline std::array<Vec3, 8> boxCorners(const Vec3& c, const Eigen::Matrix3d& R, const Vec3& h) {
  std::array<Vec3, 8> v;
  for (int i = 0; i < 8; ++i)
    v[i] =
        c + R * Vec3((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  return v;
}

/// Two oriented boxes overlap (touching counts): 15 axes, every corner projected.
inline bool obbObbOverlap(const Vec3& ca, const Eigen::Matrix3d& Ra, const Vec3& ha, const Vec3& cb,
                          const Eigen::Matrix3d& Rb, const Vec3& hb) {
  const auto A = boxCorners(ca, Ra, ha), B = boxCorners(cb, Rb, hb);
  std::vector<Vec3> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(Ra.col(i)), axes.push_back(Rb.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Vec3 n = Ra.col(i).cross(Rb.col(j));
      if (n.norm() > 1e-9) axes.push_back(n.normalized());
    }
  for (const Vec3& n : axes) {
    double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300;
    for (const Vec3& p : A) a0 = std::min(a0, n.dot(p)), a1 = std::max(a1, n.dot(p));
    for (const Vec3& p : B) b0 = std::min(b0, n.dot(p)), b1 = std::max(b1, n.dot(p));
    if (a1 < b0 || b1 < a0) return false;
  }
  return true;
}

/// Distance from p to the axis-aligned box [lo, hi] via its closest point.
inline double pointBoxDistance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p - p.cwiseMax(lo).cwiseMin(hi)).norm();
}

/// Closest distance between segments [p1, q1] and [p2, q2] (Ericson 5.1.9).
inline double segmentSegmentDistance(const Vec3& p1, const Vec3& q1, const Vec3& p2,
                                     const Vec3& q2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 1e-18 && e <= 1e-18) return r.norm();
  if (a <= 1e-18) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-18) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 1e-18 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0)
        t = 0, s = std::clamp(-c / a, 0.0, 1.0);
      else if (t > 1)
        t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
    }
  }
  return ((p1 + d1 * s) - (p2 + d2 * t)).norm();
}

/// Distance from the segment [a, b] to the box [lo, hi]: 0 when the segment enters it (slabs),
/// else the least of the end points' distances and the distances to the 12 box edges.
inline double segmentBoxDistance(const Vec3& a, const Vec3& b, const Vec3& lo, const Vec3& hi) {
  double t0 = 0, t1 = 1;
  bool enters = true;
  for (int i = 0; i < 3 && enters; ++i) {
    const double d = b[i] - a[i];
    if (std::abs(d) < 1e-15) {
      if (a[i] < lo[i] || a[i] > hi[i]) enters = false;
      continue;
    }
    double u0 = (lo[i] - a[i]) / d, u1 = (hi[i] - a[i]) / d;
    if (u0 > u1) std::swap(u0, u1);
    t0 = std::max(t0, u0), t1 = std::min(t1, u1);
    if (t0 > t1) enters = false;
  }
  if (enters) return 0.0;
  double best = std::min(pointBoxDistance(a, lo, hi), pointBoxDistance(b, lo, hi));
  for (int axis = 0; axis < 3; ++axis)
    for (int k = 0; k < 4; ++k) {
      Vec3 e0 = lo, e1;
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      e0[u] = (k & 1) ? hi[u] : lo[u];
      e0[v] = (k & 2) ? hi[v] : lo[v];
      e1 = e0;
      e1[axis] = hi[axis];
      best = std::min(best, segmentSegmentDistance(a, b, e0, e1));
    }
  return best;
}

/// Whether p is strictly inside a convex closed mesh: on the vertex centroid's side of every
/// face plane (whatever the winding).
inline bool insideConvex(const geometry::TriangleMesh& mesh, const Vec3& p) {
  Vec3 centroid = Vec3::Zero();
  for (const auto& v : mesh.vertices_m) centroid += v.cast<double>();
  centroid /= double(mesh.vertices_m.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Vec3 a = mesh.vertices_m[t[0]].cast<double>(), b = mesh.vertices_m[t[1]].cast<double>(),
               c = mesh.vertices_m[t[2]].cast<double>();
    const Vec3 n = (b - a).cross(c - a);
    if (n.dot(p - a) * n.dot(centroid - a) <= 0) return false;
  }
  return true;
}

/// Cell `k` counts as an obstacle for these options (state from the map; no block: unknown).
inline bool isObstacle(const Map& map, const VoxelKey& k, bool unknown_is_occupied) {
  const Cell* c = map.findCell(k);
  const CellState s = c ? map.state(*c) : CellState::kUnknown;
  return s == CellState::kOccupied || (unknown_is_occupied && s == CellState::kUnknown);
}

/// Every obstacle cell within `range_m` of `centre` for which overlaps(cell centre, shrunk
/// half) holds.
inline std::vector<VoxelKey> bruteForce(const Map& map, const Vec3& centre, double range_m,
                                        bool unknown_is_occupied,
                                        const std::function<bool(const Vec3&, double)>& overlaps) {
  const VoxelKey lo = map.keyOf(centre - Vec3::Constant(range_m));
  const VoxelKey hi = map.keyOf(centre + Vec3::Constant(range_m));
  const double half = 0.5 * map.resolution() - kTouchEpsilon_m;
  std::vector<VoxelKey> hits;
  for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y)
      for (int x = lo.x; x <= hi.x; ++x) {
        const VoxelKey k{x, y, z};
        if (isObstacle(map, k, unknown_is_occupied) && overlaps(map.centerOf(k), half))
          hits.push_back(k);
      }
  return hits;
}

inline Eigen::Isometry3d randomPose(std::mt19937& rng, double spread_m) {
  std::uniform_real_distribution<double> pos(-spread_m, spread_m), u(-1.0, 1.0);
  Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
  if (q.norm() < 1e-3) q = Eigen::Quaterniond::Identity();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Vec3(pos(rng), pos(rng), pos(rng));
  return T;
}

/// A map at `resolution_m` whose cells in [-extent, extent) voxels are occupied, free, unknown
/// band or left without a value at random (some blocks never created).
inline Map randomMap(double resolution_m, int extent_vox, uint32_t seed) {
  MapParams params;
  params.resolution_m = resolution_m;
  Map map(params);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, 99);
  map.writeCells([&](CellWriter& w) {
    for (int z = -extent_vox; z < extent_vox; ++z)
      for (int y = -extent_vox; y < extent_vox; ++y)
        for (int x = -extent_vox; x < extent_vox; ++x) {
          if (x >= extent_vox / 2 && y >= extent_vox / 2) continue;  // a corner of no blocks
          const int p = pick(rng);
          if (p < 4)
            w.set({x, y, z}, Cell{1, 3000});  // occupied
          else if (p < 60)
            w.set({x, y, z}, Cell{0, -2000});  // free
          else if (p < 70)
            w.set({x, y, z}, Cell{0, 0});  // unknown band (p = 0.5)
        }
  });
  return map;
}

}  // namespace fragg::planning::test
