// SubmapRegion and MergeMode (fragg_map/submap.h): membership, validation, names.
#include <cmath>
#include <string>

#include "fragg_map/errors.h"
#include "fragg_map/submap.h"

namespace fragg {

SubmapRegion SubmapRegion::box(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map) {
  SubmapRegion r;
  r.kind = Kind::kBox;
  r.min_map = min_map;
  r.max_map = max_map;
  r.validate();
  return r;
}

SubmapRegion SubmapRegion::outsideSphere(const Eigen::Vector3d& center_map, double radius_m) {
  SubmapRegion r;
  r.kind = Kind::kOutsideSphere;
  r.center_map = center_map;
  r.radius_m = radius_m;
  r.validate();
  return r;
}

bool SubmapRegion::contains(const Eigen::Vector3d& p_map) const {
  switch (kind) {
    case Kind::kBox:
      return (p_map.array() >= min_map.array()).all() && (p_map.array() <= max_map.array()).all();
    case Kind::kOutsideSphere:
      return (p_map - center_map).norm() > radius_m;
    case Kind::kNone:
      break;
  }
  return false;
}

void SubmapRegion::validate() const {
  switch (kind) {
    case Kind::kNone:
      break;
    case Kind::kBox:
      if (!min_map.allFinite() || !max_map.allFinite())
        throw InvalidArgument("sub-map box corners must be finite");
      if ((min_map.array() > max_map.array()).any())
        throw InvalidArgument("sub-map box min corner must not exceed the max corner");
      break;
    case Kind::kOutsideSphere:
      if (!center_map.allFinite()) throw InvalidArgument("sub-map centre must be finite");
      if (!std::isfinite(radius_m) || radius_m < 0.0)
        throw InvalidArgument("sub-map radius must be finite and >= 0, got " +
                              std::to_string(radius_m));
      break;
    default:
      throw InvalidArgument("unknown sub-map region kind " +
                            std::to_string(static_cast<uint32_t>(kind)));
  }
  if (frame_id.size() > kMaxRegionFrameChars)
    throw InvalidArgument("sub-map frame id longer than " + std::to_string(kMaxRegionFrameChars) +
                          " characters");
}

const char* toString(MergeMode m) { return m == MergeMode::kAdd ? "add" : "overwrite"; }

MergeMode mergeModeFromString(const std::string& s) {
  if (s == "overwrite") return MergeMode::kOverwrite;
  if (s == "add") return MergeMode::kAdd;
  throw InvalidArgument("merge mode must be overwrite or add, got '" + s + "'");
}

}  // namespace fragg
