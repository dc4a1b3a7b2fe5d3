#include "render_layout.h"

#include <fmt/format.h>

#include <algorithm>

#include "fragg_map/errors.h"

namespace fragg::internal {
namespace {

/// Smallest voxels-per-pixel that keeps `voxels` within `max_cells` grid pixels.
int64_t voxelsPerPixel(int64_t voxels, int64_t max_cells) {
  return (voxels + max_cells - 1) / max_cells;
}

void validate(const RenderOptions& options) {
  if (options.max_side_px < 1)
    throw InvalidArgument(
        fmt::format("render: max_side_px must be >= 1, got {}", options.max_side_px));
  if (options.scale < 1 || options.scale > options.max_side_px)
    throw InvalidArgument(fmt::format("render: scale must be in [1, {}] pixels per voxel, got {}",
                                      options.max_side_px, options.scale));
  if (options.crop) {
    const Eigen::AlignedBox3d& box = *options.crop;
    if (!box.min().allFinite() || !box.max().allFinite() || box.isEmpty())
      throw InvalidArgument("render: the crop box must be finite with min <= max on every axis");
  }
}

}  // namespace

RenderLayout renderLayout(const Map& map, const RenderOptions& options) {
  validate(options);
  RenderLayout layout;
  layout.scale = options.scale;
  if (options.crop) {
    layout.lo = map.keyOf(options.crop->min());
    layout.hi = map.keyOf(options.crop->max());
    layout.cropped = true;
  } else {
    const KeyBounds bounds = map.bounds();
    if (bounds.empty)
      throw InvalidArgument("render: nothing to draw: the map has no observed cell");
    layout.lo = bounds.min;
    layout.hi = bounds.max;
  }
  const int64_t nx = int64_t{layout.hi.x} - layout.lo.x + 1;
  const int64_t ny = int64_t{layout.hi.y} - layout.lo.y + 1;
  const int64_t max_cells = options.max_side_px / options.scale;
  if (nx > max_cells || ny > max_cells) {
    if (!options.auto_downscale)
      throw InvalidArgument(fmt::format(
          "render: the image would be {} x {} px, more than the {} px allowed per side (lower "
          "the scale, crop, or allow downscaling)",
          nx * options.scale, ny * options.scale, options.max_side_px));
    // Fewer pixels per voxel first; several voxels per pixel only when one pixel is too many.
    const int64_t n = std::max(nx, ny);
    if (n <= options.max_side_px) {
      layout.scale = static_cast<int>(options.max_side_px / n);
    } else {
      layout.scale = 1;
      layout.vpp = voxelsPerPixel(n, options.max_side_px);
    }
  }
  layout.grid_w = static_cast<int>((nx + layout.vpp - 1) / layout.vpp);
  layout.grid_h = static_cast<int>((ny + layout.vpp - 1) / layout.vpp);
  return layout;
}

std::vector<uint8_t> scaleToImage(const RenderLayout& layout, const std::vector<Rgb>& grid) {
  const size_t width = static_cast<size_t>(layout.widthPx());
  const size_t row_bytes = width * 3;
  std::vector<uint8_t> rgb(row_bytes * layout.heightPx());
  for (int gy = 0; gy < layout.grid_h; ++gy) {
    uint8_t* first = &rgb[static_cast<size_t>(gy) * layout.scale * row_bytes];
    for (int gx = 0; gx < layout.grid_w; ++gx) {
      const Rgb c = grid[static_cast<size_t>(gy) * layout.grid_w + gx];
      for (int s = 0; s < layout.scale; ++s) {
        uint8_t* px = first + (static_cast<size_t>(gx) * layout.scale + s) * 3;
        px[0] = c.r;
        px[1] = c.g;
        px[2] = c.b;
      }
    }
    for (int s = 1; s < layout.scale; ++s)
      std::copy(first, first + row_bytes, first + static_cast<size_t>(s) * row_bytes);
  }
  return rgb;
}

}  // namespace fragg::internal
