// octomap_server's occupancy_min_z / occupancy_max_z: the heights whose cells the server shows.
// A cell is shown (occupied and free markers, the occupied-cell cloud, the projected map) when
// its cube overlaps the open band (min_z, max_z), as octomap_server decides it per leaf.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "fragg_map/errors.h"
#include "fragg_map/key.h"

namespace fragg::ros {

struct HeightBand {
  double min_z_m = -std::numeric_limits<double>::infinity();
  double max_z_m = std::numeric_limits<double>::infinity();

  /// Throws InvalidArgument for a NaN bound or min_z above max_z.
  void validate() const {
    if (std::isnan(min_z_m) || std::isnan(max_z_m))
      throw fragg::InvalidArgument("occupancy_min_z / occupancy_max_z must not be NaN");
    if (min_z_m > max_z_m) throw fragg::InvalidArgument("occupancy_min_z exceeds occupancy_max_z");
  }

  bool unbounded() const { return std::isinf(min_z_m) && std::isinf(max_z_m); }

  /// Whether the cell whose centre is at height `center_z_m` (cube of side `res_m`) is shown.
  bool showsCell(double center_z_m, double res_m) const {
    return center_z_m + 0.5 * res_m > min_z_m && center_z_m - 0.5 * res_m < max_z_m;
  }

  /// Whether cells of voxel layer `voxel_z` (key) are shown.
  bool showsLayer(int64_t voxel_z, double res_m) const {
    return showsCell((static_cast<double>(voxel_z) + 0.5) * res_m, res_m);
  }

  /// Bit z set: the cells of layer z of blocks at block height `block_z` are shown.
  uint8_t blockLayers(int32_t block_z, double res_m) const {
    uint8_t layers = 0;
    for (int z = 0; z < fragg::kBlockSize; ++z)
      if (showsLayer(int64_t{block_z} * fragg::kBlockSize + z, res_m)) layers |= uint8_t(1u << z);
    return layers;
  }
};

}  // namespace fragg::ros
