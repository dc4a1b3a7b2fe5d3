// Small maps for the map -> message converter tests: cells written directly, or scans of a
// wall inserted through the CPU backend.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "fragg_map/map.h"

namespace fragg::ros::test {

inline fragg::MapParams cpuParams(double resolution_m = 0.1) {
  fragg::MapParams p;
  p.resolution_m = resolution_m;
  p.backend = fragg::Backend::kCpu;
  p.threads = 1;
  return p;
}

/// Writes one cell (occupied: hit log-odds; free: miss log-odds) and marks its block changed
/// at the map's new revision.
inline void setCell(fragg::Map& map, const fragg::VoxelKey& v, fragg::CellState state) {
  fragg::Cell c;
  if (state != fragg::CellState::kUnknown) {
    c.hits = state == fragg::CellState::kOccupied ? 1 : 0;
    c.log_odds_fx = state == fragg::CellState::kOccupied ? map.model().max_fx : map.model().min_fx;
  }
  map.writeCells([&](fragg::CellWriter& cells) { cells.set(v, c); });
}

/// A 2 m x 2 m wall of points `distance_m` ahead (+x) of the sensor at `sensor_xyz`.
inline void insertWall(fragg::Map& map, const Eigen::Vector3d& sensor_xyz, double distance_m) {
  fragg::PointCloud cloud;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j)
      cloud.points_S.emplace_back(static_cast<float>(distance_m), -1.f + 0.05f * i,
                                  -1.f + 0.05f * j);
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  T_map_sensor.translation() = sensor_xyz;
  map.insert(cloud, T_map_sensor, fragg::SensorModel::autoFromCloud(0.0, -1.0));
}

/// Every cell of the map in `state`, as voxel centres.
inline std::vector<Eigen::Vector3d> centresIn(const fragg::Map& map, fragg::CellState state) {
  std::vector<Eigen::Vector3d> out;
  map.forEachBlock([&](const fragg::BlockKey& key, const fragg::Block& block) {
    for (int c = 0; c < fragg::kCellsPerBlock; ++c)
      if (map.state(block.cells[c]) == state)
        out.push_back(map.centerOf(fragg::voxelKeyOf(key, c)));
  });
  return out;
}

}  // namespace fragg::ros::test
