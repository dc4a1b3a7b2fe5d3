// The angle between a multi-beam LiDAR's neighbouring beams, estimated from its clouds, so that
// the node can choose the frontier grid (coarse_map.h, coarseCellsForBeams) from the sensor it
// is fed without being told the sensor's model (issue 34 item 5).
//
// Estimate: points grouped by azimuth into 1-degree wedges, over which a spinning LiDAR's beam
// keeps its elevation; in each wedge the elevations, sorted, step from beam to beam; the median
// of those steps (steps of less than 0.02 degree, two points of one beam, left out) is the
// vertical beam spacing. (Wedges narrower than the horizontal step would split one column's
// beams between two wedges and double the steps.) Beams that
// returned nothing make some steps twice as long, which the median ignores. The range the
// spacing matters at is the far end of the cloud: the 99th percentile of the points' ranges.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <vector>

namespace fragg::planning {

struct BeamSpacing {
  double angle_rad = 0.0;  ///< between vertically neighbouring beams
  double range_m = 0.0;    ///< the cloud's far range (99th percentile of its points' ranges)
};

/// The beam spacing of one cloud (sensor frame, x forward, z up; NaN points skipped), or
/// nullopt when the cloud does not look like a multi-beam LiDAR's (fewer than 1,000 usable
/// points beyond 1 m, too few beam steps, or a spacing outside 0.03-10 degrees).
[[nodiscard]] std::optional<BeamSpacing> estimateBeamSpacing(
    const std::vector<Eigen::Vector3f>& points_S);

/// The estimates of the first few clouds a node received, combined: the median angle and the
/// median far range of the estimates so far. Not thread-safe (the node keeps it with its map,
/// under the map's lock).
class BeamSpacingTracker {
 public:
  static constexpr size_t kClouds = 5;  ///< estimates kept; later clouds are not looked at

  /// Whether another cloud's estimate would be used.
  [[nodiscard]] bool wantsMore() const { return angles_.size() < kClouds; }
  /// Adds one cloud's estimate.
  void add(const BeamSpacing& b);
  /// The combined estimate; nullopt before the first.
  [[nodiscard]] std::optional<BeamSpacing> estimate() const;

 private:
  std::vector<double> angles_, ranges_;
};

}  // namespace fragg::planning
