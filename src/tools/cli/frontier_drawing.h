// Frontiers drawn over a rendered top view (fragg_map render --frontiers): the map faded
// towards mid grey, each cluster's cells as filled cell squares in the cluster's colour (fully
// saturated, so never mistaken for the faded map), each viewpoint as a disc with a line along
// its heading (the best one of a cluster larger).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>

#include "cli/frontier_options.h"
#include "fragg_map/interop/render.h"
#include "fragg_map/map.h"

namespace fragg::cli {

/// A saturated colour per cluster id (12 colours in turn), none of them the map's grey, black
/// or the viewpoint white.
Rgb clusterColor(uint64_t id);

/// Halves the image's contrast towards mid grey: every channel c becomes (c + 128) / 2 (so
/// within [64, 191]), which keeps the map readable under the clusters' colours.
void fadeForOverlay(RenderImage& image);

/// Fills the pixels the x/y square of cell `key` of `map` covers on `image` (rendered from
/// `map`), at least the one under its centre.
void fillCellSquare(RenderImage& image, const Map& map, const VoxelKey& key, const Rgb& color);

/// The viewpoints' fill colour and outline.
inline constexpr Rgb kViewpointColor{255, 255, 255};
inline constexpr Rgb kViewpointOutline{0, 0, 0};

struct FrontierDrawStats {
  uint64_t cells_drawn = 0;       ///< clustered cells inside the crop box
  uint64_t viewpoints_drawn = 0;  ///< viewpoints inside the crop box
};

/// Draws `result` onto `image` (rendered from `map`); cells and viewpoints whose centre is outside
/// `crop` (when given) are left out.
FrontierDrawStats drawFrontiers(RenderImage& image, const Map& map, const FrontierResult& result,
                                const std::optional<Eigen::AlignedBox3d>& crop);

}  // namespace fragg::cli
