// Geometry of a rendered image: which voxels it covers and how voxels map to pixels.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fragg_map/interop/render.h"

namespace fragg::internal {

struct RenderLayout {
  VoxelKey lo, hi;  ///< inclusive voxel range drawn
  int64_t vpp = 1;  ///< voxels per grid pixel, per axis
  int scale = 1;    ///< image pixels per grid pixel, per axis
  int grid_w = 0;   ///< grid pixels (before scaling)
  int grid_h = 0;
  bool cropped = false;  ///< the range comes from a crop box

  int widthPx() const { return grid_w * scale; }
  int heightPx() const { return grid_h * scale; }
  bool contains(const VoxelKey& v) const {
    return v.x >= lo.x && v.x <= hi.x && v.y >= lo.y && v.y <= hi.y && v.z >= lo.z && v.z <= hi.z;
  }
  /// Grid pixel of a voxel column inside the range; y grows upwards, so the top row is hi.y.
  size_t gridIndex(const VoxelKey& v) const {
    const int64_t col = (int64_t{v.x} - lo.x) / vpp;
    const int64_t row = (int64_t{hi.y} - v.y) / vpp;
    return static_cast<size_t>(row) * grid_w + static_cast<size_t>(col);
  }
};

/// The x/y range from the crop box (else the observed bounds), the z range from the crop box
/// (else the observed bounds), and the pixel size from the options. Throws InvalidArgument
/// for bad options, an empty map without a crop box, or an image too large to draw without
/// downscaling when auto_downscale is off.
RenderLayout renderLayout(const Map& map, const RenderOptions& options);

/// Scales a grid of colours (grid_w * grid_h) up to the image (each grid pixel becomes a
/// scale x scale square) as packed RGB rows.
std::vector<uint8_t> scaleToImage(const RenderLayout& layout, const std::vector<Rgb>& grid);

}  // namespace fragg::internal
