// Ghost cells drawn over a rendered top view (fragg_map render --highlight-ghosts): the map
// faded towards mid grey (fadeForOverlay), each column holding a ghost cell -- occupied in the
// map, free in the static truth, as `fragg_map eval` counts them (sim/dynamic_quality.h) -- in
// pure red, which the faded height ramp never shows.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/interop/render.h"
#include "fragg_map/map.h"

namespace fragg::cli {

/// The ghosts' colour.
inline constexpr Rgb kGhostColor{255, 0, 0};

struct GhostDrawStats {
  uint64_t ghost_cells = 0;  ///< ghost cells of the map (all of them)
  uint64_t cells_drawn = 0;  ///< those whose centre is inside the crop box
};

/// Fades `image` (rendered from `map`) and draws the columns of the map's ghost cells against
/// `static_scene` in kGhostColor; cells whose centre is outside `crop` (when given) are left
/// out.
GhostDrawStats drawGhosts(RenderImage& image, const Map& map, const geometry::MeshBvh& static_scene,
                          const std::optional<Eigen::AlignedBox3d>& crop);

}  // namespace fragg::cli
