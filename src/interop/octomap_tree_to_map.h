// Conversion of any OctoMap occupancy tree (OcTree, ColorOcTree, OcTreeStamped) into a Map.
#pragma once

#include <fmt/format.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "fragg_map/cell_writer.h"
#include "fragg_map/errors.h"
#include "fragg_map/interop/octomap_io.h"
#include "fragg_map/map.h"
#include "fragg_map/map_params.h"

namespace fragg::internal {

/// Map parameters from a tree's resolution and occupancy parameters; the unknown band keeps
/// its default (OctoMap has none). Throws IoError when the tree's values are unusable.
MapParams mapParamsOfTree(double resolution_m, double prob_hit, double prob_miss, double clamp_min,
                          double clamp_max, const std::string& source);

/// Fixed-point log-odds of an OctoMap node value, clamped to the int16 range (INT16_MIN
/// excluded: it marks unobserved cells). Throws IoError for a non-finite value.
int16_t logOddsFxOfNode(float log_odds, const std::string& source);

template <class Tree>
Map mapFromTree(const Tree& tree, const std::string& source, Backend backend) {
  MapParams params =
      mapParamsOfTree(tree.getResolution(), tree.getProbHit(), tree.getProbMiss(),
                      tree.getClampingThresMin(), tree.getClampingThresMax(), source);
  params.backend = backend;
  Map map(params);
  const int depth = static_cast<int>(tree.getTreeDepth());
  const int32_t key_offset = int32_t{1} << (depth - 1);  // OctoMap's tree_max_val
  uint64_t voxels = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const uint64_t edge = uint64_t{1} << (depth - static_cast<int>(it.getDepth()));
    voxels += edge * edge * edge;
    if (voxels > kMaxImportVoxels)
      throw IoError(fmt::format(
          "{}: the tree's leaves expand to more than {} voxels at {} m (coarse leaves cover "
          "too much space to convert)",
          source, kMaxImportVoxels, tree.getResolution()));
  }
  map.writeCells([&](CellWriter& cells) {
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      const int16_t fx = logOddsFxOfNode(it->getLogOdds(), source);
      const octomap::OcTreeKey k = it.getIndexKey();
      const VoxelKey lo{static_cast<int32_t>(k[0]) - key_offset,
                        static_cast<int32_t>(k[1]) - key_offset,
                        static_cast<int32_t>(k[2]) - key_offset};
      cells.fillCube(lo, int32_t{1} << (depth - static_cast<int>(it.getDepth())), fx);
    }
  });
  return map;
}

}  // namespace fragg::internal
