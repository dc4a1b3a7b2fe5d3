// A spinning LiDAR's beam table: the elevations of its rings and the columns of one revolution.
// With it, an unorganised cloud (no NaN placeholders, e.g. a KITTI .bin or a driver that drops
// no-returns) still tells which beams returned nothing: its points are binned into
// (ring, column) and every empty bin is a no-return beam (MapParams::clear_no_return_rays).
// Sensor frame: x forward, y left, z up; column c's azimuth is azimuth_offset_rad + 2 pi c /
// columns, counter-clockwise from +x.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace fragg {

/// Largest beam tables LidarBeams::validate() accepts.
constexpr uint32_t kMaxLidarRings = 4096;
constexpr uint32_t kMaxLidarColumns = 100000;

struct LidarBeams {
  /// Elevation of each ring above the sensor's xy plane, radians, strictly increasing.
  std::vector<double> ring_elevations_rad;
  /// Columns (firings) a revolution; 0 only with no rings.
  uint32_t columns = 0;
  /// Azimuth of column 0, radians counter-clockwise from +x.
  double azimuth_offset_rad = 0.0;

  /// No table: the sensor gives no beam layout.
  [[nodiscard]] bool empty() const { return ring_elevations_rad.empty(); }
  /// Rings in the table.
  [[nodiscard]] uint32_t rings() const { return uint32_t(ring_elevations_rad.size()); }

  /// `rings` rings evenly spaced from `elevation_min_rad` to `elevation_max_rad` (both
  /// included; one ring sits at the top), as most spinning LiDARs' data sheets give them.
  /// Throws InvalidArgument on a bad count or range.
  static LidarBeams evenlySpaced(uint32_t rings, uint32_t columns, double elevation_min_rad,
                                 double elevation_max_rad);

  /// Throws InvalidArgument naming the bad field (sensor.lidar_rings, sensor.lidar_columns,
  /// sensor.lidar_ring_elevations_rad, sensor.lidar_azimuth_offset_rad). An empty table passes.
  void validate() const;

  /// The ring whose elevation is nearest `elevation_rad`, or -1 when the elevation lies more
  /// than half the gap to the neighbouring ring outside the table.
  [[nodiscard]] int ringOf(double elevation_rad) const;
  /// The column whose azimuth is nearest `azimuth_rad` (any angle; wraps).
  [[nodiscard]] uint32_t columnOf(double azimuth_rad) const;
  /// The unit direction of beam (ring, column) in the sensor frame.
  [[nodiscard]] Eigen::Vector3d direction(uint32_t ring, uint32_t column) const;
};

}  // namespace fragg
