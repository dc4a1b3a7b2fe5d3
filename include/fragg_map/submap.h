// Sub-maps (issue 13): a map plus the region it was cut from. Map::extract / truncate /
// truncateOutside cut one out, Map::merge puts one (or a map from another robot) back.
//
// A cell belongs to a region by its centre: a box holds the cells whose centres lie in
// [min_map, max_map] (inclusive); an "outside" sphere holds the cells whose centres are
// farther than radius_m from centre_map.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>

namespace fragg {

/// Where a sub-map was cut from, in the frame `frame_id` of the map it came from.
struct SubmapRegion {
  enum class Kind : uint32_t { kNone = 0, kBox = 1, kOutsideSphere = 2 };
  Kind kind = Kind::kNone;
  Eigen::Vector3d min_map = Eigen::Vector3d::Zero();     ///< kBox
  Eigen::Vector3d max_map = Eigen::Vector3d::Zero();     ///< kBox
  Eigen::Vector3d center_map = Eigen::Vector3d::Zero();  ///< kOutsideSphere
  double radius_m = 0.0;                                 ///< kOutsideSphere
  std::string frame_id = "map";

  static SubmapRegion box(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map);
  static SubmapRegion outsideSphere(const Eigen::Vector3d& center_map, double radius_m);
  bool empty() const { return kind == Kind::kNone; }
  /// Whether a point (a cell centre) belongs to the region. kNone holds nothing.
  bool contains(const Eigen::Vector3d& p_map) const;
  /// InvalidArgument for non-finite values, an inverted box, a negative radius or a frame id
  /// longer than kMaxRegionFrameChars.
  void validate() const;
};

constexpr size_t kMaxRegionFrameChars = 256;

/// How Map::merge combines a sub-map cell with the map's cell at the same place.
enum class MergeMode : uint8_t {
  /// An observed sub-map cell replaces the map's cell; an unobserved one leaves it.
  kOverwrite = 0,
  /// Log-odds add, clamped to the map's clamping range; hit counts add, saturating at
  /// INT16_MAX. An unobserved cell plus an observed one is the observed one.
  kAdd = 1,
};
const char* toString(MergeMode m);
MergeMode mergeModeFromString(const std::string& s);  ///< "overwrite" | "add"

/// What an extract, truncate or merge did.
struct SubmapStats {
  uint64_t cells = 0;   ///< observed cells copied, moved or merged
  uint64_t blocks = 0;  ///< blocks of the sub-map (extract/truncate) or blocks written (merge)
  uint64_t blocks_erased = 0;  ///< truncate: blocks of the map left empty and erased
  double seconds_total = 0.0;
};

}  // namespace fragg
