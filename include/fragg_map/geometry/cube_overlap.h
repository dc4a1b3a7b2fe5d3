// Exact overlap tests between a closed shape and an axis-aligned cube (a map cell): oriented
// box, sphere, segment (capsule axis) and triangle. Touching counts in every test here: the
// collision checker passes a cube shrunk by its touching epsilon so that "touching is not a
// collision" is decided in one place. FRAGG_HD: the CPU checker and, later, the CUDA collision
// kernel share them.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "fragg_map/hd.h"

namespace fragg::geometry {

/// Squared distance from p to the cube centre +- half (0 inside).
FRAGG_HD double pointCubeDistanceSq(const Eigen::Vector3d& p, const Eigen::Vector3d& centre,
                                    double half) {
  double d_sq = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double excess = fabs(p[i] - centre[i]) - half;
    if (excess > 0.0) d_sq += excess * excess;
  }
  return d_sq;
}

/// Whether the oriented box (centre box_centre, unit axes = columns of R, half extents
/// box_half) meets the cube centre +- half: separating axis test over the cube's 3 axes, the
/// box's 3 and their 9 cross products.
FRAGG_HD bool orientedBoxCubeOverlap(const Eigen::Vector3d& box_centre, const Eigen::Matrix3d& R,
                                     const Eigen::Vector3d& box_half, const Eigen::Vector3d& centre,
                                     double half) {
  const Eigen::Vector3d t = box_centre - centre;
  for (int i = 0; i < 3; ++i) {  // cube axes
    const double rb =
        box_half[0] * fabs(R(i, 0)) + box_half[1] * fabs(R(i, 1)) + box_half[2] * fabs(R(i, 2));
    if (fabs(t[i]) > half + rb) return false;
  }
  for (int j = 0; j < 3; ++j) {  // box axes
    const Eigen::Vector3d b = R.col(j);
    const double ra = half * (fabs(b[0]) + fabs(b[1]) + fabs(b[2]));
    if (fabs(t.dot(b)) > ra + box_half[j]) return false;
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {  // cross products
      const Eigen::Vector3d axis = Eigen::Vector3d::Unit(i).cross(R.col(j));
      // (Nearly) parallel: the face axes decide; a cross product shorter than 1e-6 has a
      // direction too noisy to separate with, and skipping it errs by < 1e-6 of the sizes.
      if (axis.squaredNorm() < 1e-12) continue;
      const double ra = half * (fabs(axis[0]) + fabs(axis[1]) + fabs(axis[2]));
      const double rb = box_half[0] * fabs(axis.dot(R.col(0))) +
                        box_half[1] * fabs(axis.dot(R.col(1))) +
                        box_half[2] * fabs(axis.dot(R.col(2)));
      if (fabs(t.dot(axis)) > ra + rb) return false;
    }
  return true;
}

/// Squared distance from the segment [a, b] to the cube centre +- half. The squared distance to
/// a convex set is convex along the segment, so a golden-section search finds its minimum
/// (100 steps: the parameter to 1e-20 of the segment's length).
FRAGG_HD double segmentCubeDistanceSq(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& centre, double half) {
  const Eigen::Vector3d d = b - a;
  const double kInvPhi = 0.6180339887498949;
  double lo = 0.0, hi = 1.0;
  double x1 = hi - kInvPhi * (hi - lo), x2 = lo + kInvPhi * (hi - lo);
  double f1 = pointCubeDistanceSq(a + x1 * d, centre, half);
  double f2 = pointCubeDistanceSq(a + x2 * d, centre, half);
  for (int step = 0; step < 100 && f1 + f2 > 0.0; ++step) {
    if (f1 <= f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - kInvPhi * (hi - lo);
      f1 = pointCubeDistanceSq(a + x1 * d, centre, half);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + kInvPhi * (hi - lo);
      f2 = pointCubeDistanceSq(a + x2 * d, centre, half);
    }
  }
  double best = f1 < f2 ? f1 : f2;
  const double fa = pointCubeDistanceSq(a, centre, half);
  const double fb = pointCubeDistanceSq(b, centre, half);
  if (fa < best) best = fa;
  if (fb < best) best = fb;
  return best;
}

/// Whether the triangle (a, b, c) meets the cube centre +- half (separating axis test of
/// Akenine-Moller: the cube's 3 axes, the triangle's normal, 9 edge cross products).
FRAGG_HD bool triangleCubeOverlap(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c, const Eigen::Vector3d& centre,
                                  double half) {
  const Eigen::Vector3d v0 = a - centre, v1 = b - centre, v2 = c - centre;
  for (int i = 0; i < 3; ++i) {
    const double lo = fmin(v0[i], fmin(v1[i], v2[i]));
    const double hi = fmax(v0[i], fmax(v1[i], v2[i]));
    if (lo > half || hi < -half) return false;
  }
  const Eigen::Vector3d e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
  const Eigen::Vector3d n = e0.cross(e1);
  if (fabs(n.dot(v0)) > half * (fabs(n[0]) + fabs(n[1]) + fabs(n[2]))) return false;
  const Eigen::Vector3d edges[3] = {e0, e1, e2};
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d axis = Eigen::Vector3d::Unit(i).cross(edges[j]);
      const double p0 = axis.dot(v0), p1 = axis.dot(v1), p2 = axis.dot(v2);
      const double r = half * (fabs(axis[0]) + fabs(axis[1]) + fabs(axis[2]));
      if (fmin(p0, fmin(p1, p2)) > r || fmax(p0, fmax(p1, p2)) < -r) return false;
    }
  return true;
}

}  // namespace fragg::geometry
