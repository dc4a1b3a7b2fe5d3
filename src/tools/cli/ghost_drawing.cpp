#include "cli/ghost_drawing.h"

#include <vector>

#include "cli/frontier_drawing.h"
#include "fragg_map/sim/dynamic_quality.h"

namespace fragg::cli {

GhostDrawStats drawGhosts(RenderImage& image, const Map& map, const geometry::MeshBvh& static_scene,
                          const std::optional<Eigen::AlignedBox3d>& crop) {
  const std::vector<VoxelKey> ghosts =
      sim::ghostCellKeys(map, static_scene, /*octomap_threshold=*/false);
  fadeForOverlay(image);
  GhostDrawStats stats;
  stats.ghost_cells = ghosts.size();
  for (const VoxelKey& key : ghosts) {
    if (crop && !crop->contains(map.centerOf(key))) continue;
    fillCellSquare(image, map, key, kGhostColor);
    ++stats.cells_drawn;
  }
  return stats;
}

}  // namespace fragg::cli
