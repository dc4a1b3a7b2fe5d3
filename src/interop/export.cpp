#include "fragg_map/interop/export.h"

#include <algorithm>
#include <tuple>

#include "fragg_map/io/point_file.h"

namespace fragg {

std::vector<Eigen::Vector3f> occupiedCenters(const Map& map) {
  const OccupancyModel& model = map.model();
  std::vector<VoxelKey> keys;
  map.forEachBlock([&](const BlockKey& block_key, const Block& block) {
    for (int i = 0; i < kCellsPerBlock; ++i)
      if (model.state(block.cells[i]) == CellState::kOccupied)
        keys.push_back(voxelKeyOf(block_key, i));
  });
  std::sort(keys.begin(), keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  std::vector<Eigen::Vector3f> centers;
  centers.reserve(keys.size());
  for (const VoxelKey& k : keys) centers.push_back(map.centerOf(k).cast<float>());
  return centers;
}

size_t exportOccupiedPly(const Map& map, const std::string& path_ply) {
  const std::vector<Eigen::Vector3f> centers = occupiedCenters(map);
  writePly(path_ply, centers);
  return centers.size();
}

size_t exportOccupiedPcd(const Map& map, const std::string& path_pcd) {
  const std::vector<Eigen::Vector3f> centers = occupiedCenters(map);
  writePcd(path_pcd, centers);
  return centers.size();
}

}  // namespace fragg
