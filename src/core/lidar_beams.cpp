#include "fragg_map/lidar_beams.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "fragg_map/errors.h"

namespace fragg {

namespace {
/// Rings closer than this are one ring twice (a table typo).
constexpr double kMinRingGapRad = 1e-6;
}  // namespace

LidarBeams LidarBeams::evenlySpaced(uint32_t rings, uint32_t columns, double elevation_min_rad,
                                    double elevation_max_rad) {
  if (rings < 1 || rings > kMaxLidarRings)
    throw InvalidArgument("sensor.lidar_rings must be in [1, " + std::to_string(kMaxLidarRings) +
                          "], got " + std::to_string(rings));
  if (!(std::isfinite(elevation_min_rad) && std::isfinite(elevation_max_rad) &&
        (rings == 1 || elevation_min_rad < elevation_max_rad)))
    throw InvalidArgument(
        "sensor.lidar_rings: evenly spaced rings need sensor.elevation_min_rad below "
        "sensor.elevation_max_rad");
  LidarBeams b;
  b.columns = columns;
  b.ring_elevations_rad.resize(rings);
  for (uint32_t r = 0; r < rings; ++r)
    b.ring_elevations_rad[r] =
        rings == 1 ? elevation_max_rad
                   : elevation_min_rad + (elevation_max_rad - elevation_min_rad) * r / (rings - 1);
  b.validate();
  return b;
}

void LidarBeams::validate() const {
  if (ring_elevations_rad.empty()) {
    if (columns != 0)
      throw InvalidArgument("sensor.lidar_columns is set (" + std::to_string(columns) +
                            ") but the beam table has no rings (sensor.lidar_rings)");
    return;
  }
  if (ring_elevations_rad.size() > kMaxLidarRings)
    throw InvalidArgument("sensor.lidar_rings must be in [1, " + std::to_string(kMaxLidarRings) +
                          "], got " + std::to_string(ring_elevations_rad.size()));
  if (columns < 1 || columns > kMaxLidarColumns)
    throw InvalidArgument("sensor.lidar_columns must be in [1, " +
                          std::to_string(kMaxLidarColumns) + "], got " + std::to_string(columns));
  if (!std::isfinite(azimuth_offset_rad) || std::fabs(azimuth_offset_rad) > 2 * M_PI)
    throw InvalidArgument("sensor.lidar_azimuth_offset_rad must be in [-2 pi, 2 pi] rad");
  for (size_t r = 0; r < ring_elevations_rad.size(); ++r) {
    const double e = ring_elevations_rad[r];
    if (!(e >= -M_PI / 2 && e <= M_PI / 2))  // NaN fails too
      throw InvalidArgument("sensor.lidar_ring_elevations_rad: ring " + std::to_string(r) +
                            " must be in [-pi/2, pi/2] rad (+-90 degrees), got " +
                            std::to_string(e));
    if (r > 0 && !(e - ring_elevations_rad[r - 1] >= kMinRingGapRad))
      throw InvalidArgument("sensor.lidar_ring_elevations_rad must increase strictly: ring " +
                            std::to_string(r) + " (" + std::to_string(e) + " rad) after ring " +
                            std::to_string(r - 1) + " (" +
                            std::to_string(ring_elevations_rad[r - 1]) + " rad)");
  }
}

int LidarBeams::ringOf(double elevation_rad) const {
  const std::vector<double>& e = ring_elevations_rad;
  if (e.empty() || !std::isfinite(elevation_rad)) return -1;
  const auto it = std::lower_bound(e.begin(), e.end(), elevation_rad);
  size_t r;
  if (it == e.begin()) {
    r = 0;
  } else if (it == e.end()) {
    r = e.size() - 1;
  } else {
    const size_t hi = size_t(it - e.begin());
    r = (elevation_rad - e[hi - 1] <= e[hi] - elevation_rad) ? hi - 1 : hi;
  }
  // Beyond the outer rings: within half the gap to their neighbour (a single ring: half a
  // degree) still belongs to them.
  const double half_gap =
      e.size() == 1
          ? 0.5 * M_PI / 180.0
          : 0.5 * (r == 0 ? e[1] - e[0]
                          : (r + 1 == e.size() ? e[r] - e[r - 1]
                                               : std::max(e[r] - e[r - 1], e[r + 1] - e[r])));
  if (std::fabs(elevation_rad - e[r]) > half_gap) return -1;
  return static_cast<int>(r);
}

uint32_t LidarBeams::columnOf(double azimuth_rad) const {
  const double step = 2 * M_PI / columns;
  const double k = std::nearbyint((azimuth_rad - azimuth_offset_rad) / step);
  const double wrapped = std::fmod(k, double(columns));
  return static_cast<uint32_t>(wrapped < 0 ? wrapped + columns : wrapped);
}

Eigen::Vector3d LidarBeams::direction(uint32_t ring, uint32_t column) const {
  const double el = ring_elevations_rad[ring];
  const double az = azimuth_offset_rad + 2 * M_PI * column / columns;
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

}  // namespace fragg
