// Occupied voxel centres of a map, and writing them as point files (PLY, PCD).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "fragg_map/map.h"

namespace fragg {

/// Centres (map frame, metres) of every cell whose state is kOccupied under the map's own
/// occupancy model (unknown band included). Sorted by voxel key (z, then y, then x), so the
/// output does not depend on the block map's layout.
std::vector<Eigen::Vector3f> occupiedCenters(const Map& map);

/// Writes occupiedCenters(map) as a binary little-endian PLY / PCD file (atomic: temporary
/// file and rename). Returns the number of points written. Throws IoError when the file
/// cannot be written.
size_t exportOccupiedPly(const Map& map, const std::string& path_ply);
size_t exportOccupiedPcd(const Map& map, const std::string& path_pcd);

}  // namespace fragg
