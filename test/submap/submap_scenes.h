// Maps the sub-map tests cut and merge: the five real RGB-D frames (slambook2 ch. 5) and the
// loop tests' simulated room.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "../loop/loop_scenes.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/map.h"

namespace fragg::test {

inline const std::vector<Scan>& rgbdScans() {
  static const std::vector<Scan> scans = [] {
    std::vector<Scan> out;
    auto source = openDataset(std::string(FRAGG_REAL_DATA) + "/slambook2_ch5_rgbd");
    Scan s;
    while (source->next(s)) out.push_back(s);
    return out;
  }();
  return scans;
}

inline MapParams cpuParams(double resolution_m = 0.05) {
  MapParams p;
  p.resolution_m = resolution_m;
  p.backend = Backend::kCpu;
  return p;
}

/// A map of the RGB-D frames whose indices are listed.
inline Map rgbdMap(const std::vector<int>& frames, const MapParams& params = cpuParams()) {
  Map map(params);
  for (int i : frames) {
    const Scan& s = rgbdScans().at(i);
    map.insert(s.cloud, s.T_map_sensor, SensorModel::autoFromCloud(0.0, 8.0));
  }
  return map;
}

/// The simulated room seen from four poses (no clamping bound can be met).
inline Map roomMap(const MapParams& params = cpuParams()) {
  Map map(params);
  for (int i = 0; i < 4; ++i) map.insert(roomScan(4.0, 1.0, 2.0, 16, 360), poseAt(i), lidar());
  return map;
}

inline bool sameCell(const Cell& a, const Cell& b) {
  return a.hits == b.hits && a.log_odds_fx == b.log_odds_fx;
}

/// The cell at `key`, unobserved where the map has none.
inline Cell cellAt(const Map& map, const VoxelKey& key) {
  const Cell* c = map.findCell(key);
  return c ? *c : Cell();
}

/// Calls fn(key, cell) for every observed cell of the map.
template <typename Fn>
void forEachObserved(const Map& map, Fn&& fn) {
  map.forEachBlock([&](const BlockKey& b, const Block& block) {
    for (int c = 0; c < kCellsPerBlock; ++c)
      if (block.cells[c].observed()) fn(voxelKeyOf(b, c), block.cells[c]);
  });
}

}  // namespace fragg::test
