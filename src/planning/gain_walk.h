// Information gain along one ray (internal; shared by the CPU gain code in fragg_map_planning
// and the CUDA gain kernel, FRAGG_HD, so both walk the same cells): an exact DDA in voxel
// units, the yaw rotation of a sensor ray, and the entropy a cell adds. A batch of viewpoints
// as a backend gets it (MapBackend::viewpointGains).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "fragg_map/cell.h"
#include "fragg_map/hd.h"
#include "fragg_map/key.h"
#include "fragg_map/occupancy.h"

namespace fragg {

/// Viewpoints sharing one sensor: origin i is (origins_v[3i], [3i+1], [3i+2]) in voxel units
/// (position / resolution), its yaw as cos/sin; rays are unit directions in the sensor frame
/// (x forward, z up), 3 doubles each; every ray runs for length_v voxels.
struct GainBatch {
  std::vector<double> origins_v, cos_yaw, sin_yaw, rays_sensor;
  double length_v = 0.0;
  size_t viewpoints() const { return cos_yaw.size(); }
  size_t rays() const { return rays_sensor.size() / 3; }
};

/// Ray `in` turned by the yaw (about z), in the map frame. Plain products and sums (no FMA in
/// either build), so the host and the device get the same bits.
FRAGG_HD void yawRotate(double c, double s, const double* in, double* out) {
  out[0] = c * in[0] - s * in[1];
  out[1] = s * in[0] + c * in[1];
  out[2] = in[2];
}

/// Entropy (bits) a cell adds to a gain: 1 for never observed (or a missing block), H(p)
/// inside the unknown band, 0 for free and occupied cells.
FRAGG_HD double cellGainBits(const OccupancyModel& model, const Cell* cell) {
  if (!cell || !cell->observed()) return 1.0;
  if (model.state(*cell) != CellState::kUnknown) return 0.0;
  const double p = 1.0 - 1.0 / (1.0 + exp(static_cast<double>(cell->log_odds_fx) / kLogOddsScale));
  if (p <= 0.0 || p >= 1.0) return 0.0;
  return -(p * log2(p) + (1.0 - p) * log2(1.0 - p));
}

/// Exact voxel traversal from `origin_v` along unit `dir`: cell() is the current voxel;
/// next() steps to the following one and returns the ray parameter (voxels) where it enters.
struct GainDda {
  int cur[3], step[3];
  double t_max[3], t_delta[3];

  FRAGG_HD GainDda(const double* origin_v, const double* dir) {
    for (int a = 0; a < 3; ++a) {
      cur[a] = static_cast<int>(floor(origin_v[a]));
      if (dir[a] > 0.0) {
        step[a] = 1;
        t_delta[a] = 1.0 / dir[a];
        t_max[a] = (cur[a] + 1 - origin_v[a]) / dir[a];
      } else if (dir[a] < 0.0) {
        step[a] = -1;
        t_delta[a] = -1.0 / dir[a];
        t_max[a] = (origin_v[a] - cur[a]) / -dir[a];
      } else {
        step[a] = 0;
        t_delta[a] = t_max[a] = INFINITY;
      }
    }
  }
  FRAGG_HD VoxelKey cell() const { return VoxelKey{cur[0], cur[1], cur[2]}; }
  FRAGG_HD double next() {
    const int a =
        t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    const double t = t_max[a];
    t_max[a] += t_delta[a];
    cur[a] += step[a];
    return t;
  }
};

}  // namespace fragg
