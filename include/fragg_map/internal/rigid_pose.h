// The check every pose a map takes goes through (sensor poses, corrections, sub-map merges).
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "fragg_map/errors.h"

namespace fragg {

/// Throws InvalidArgument naming `what` unless `T` is finite and rigid: a rotation within
/// `tolerance` of orthonormal with determinant +1, and an affine last row.
inline void requireRigidPose(const Eigen::Isometry3d& T, const std::string& what,
                             double tolerance) {
  if (!T.matrix().allFinite()) throw InvalidArgument(what + " is not finite (NaN or Inf)");
  const Eigen::Matrix3d R = T.linear();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > tolerance ||
      R.determinant() < 0 ||
      (T.matrix().row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 0)
    throw InvalidArgument(what + " is not a rigid transform");
}

}  // namespace fragg
