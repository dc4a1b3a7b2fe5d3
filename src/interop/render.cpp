// Top-down height images and horizontal slices.
#include "fragg_map/interop/render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "fragg_map/errors.h"
#include "png_write.h"
#include "render_layout.h"

namespace fragg {
namespace {

using internal::RenderLayout;

/// Calls fn(voxel_key, cell) for every cell of the map inside the layout's range.
template <class Fn>
void forEachCellIn(const Map& map, const RenderLayout& layout, Fn&& fn) {
  map.forEachBlockIn(blockKeyOf(layout.lo), blockKeyOf(layout.hi),
                     [&](const BlockKey& block_key, const Block& block) {
                       for (int i = 0; i < kCellsPerBlock; ++i) {
                         const VoxelKey v = voxelKeyOf(block_key, i);
                         if (layout.contains(v)) fn(v, block.cells[i]);
                       }
                     });
}

RenderInfo infoOf(const RenderLayout& layout) {
  RenderInfo info;
  info.width_px = layout.widthPx();
  info.height_px = layout.heightPx();
  info.voxels_per_pixel = layout.vpp;
  info.scale = layout.scale;
  info.min_key = layout.lo;
  info.max_key = layout.hi;
  info.map_width_px = info.width_px;
  info.map_height_px = info.height_px;
  return info;
}

}  // namespace

Rgb heightColor(double t) {
  static constexpr Rgb kStops[] = {
      {0, 0, 255}, {0, 255, 255}, {0, 255, 0}, {255, 255, 0}, {255, 0, 0}};
  constexpr int kSegments = 4;
  const double x = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * kSegments;
  const int i = std::min(static_cast<int>(x), kSegments - 1);
  const double f = x - i;
  auto mix = [f](uint8_t a, uint8_t b) {
    return static_cast<uint8_t>(std::lround(a + (static_cast<double>(b) - a) * f));
  };
  return {mix(kStops[i].r, kStops[i + 1].r), mix(kStops[i].g, kStops[i + 1].g),
          mix(kStops[i].b, kStops[i + 1].b)};
}

RenderInfo renderTopDown(const Map& map, const std::string& path_png,
                         const RenderOptions& options) {
  RenderImage image = renderTopDownImage(map, options);
  if (options.legend) appendLegend(image, RenderView::kTop, options);
  writePng(image, path_png);
  return image.info;
}

void writePng(const RenderImage& image, const std::string& path_png) {
  internal::writePngRgb(path_png, image.info.width_px, image.info.height_px, image.rgb);
}

Eigen::Vector2d RenderImage::pixelOf(const Eigen::Vector3d& p_map) const {
  const double per_voxel =
      static_cast<double>(info.scale) / static_cast<double>(info.voxels_per_pixel);
  return Eigen::Vector2d((p_map.x() / resolution_m - info.min_key.x) * per_voxel,
                         (info.max_key.y + 1 - p_map.y() / resolution_m) * per_voxel);
}

void RenderImage::drawLine(const Eigen::Vector3d& a_map, const Eigen::Vector3d& b_map,
                           const Rgb& color, double width_px) {
  const Eigen::Vector2d a = pixelOf(a_map), b = pixelOf(b_map);
  const double r = std::max(0.5, 0.5 * width_px);
  const Eigen::Vector2d lo = a.cwiseMin(b).array() - r, hi = a.cwiseMax(b).array() + r;
  const int x0 = std::max(0, static_cast<int>(std::floor(lo.x())));
  const int y0 = std::max(0, static_cast<int>(std::floor(lo.y())));
  const int x1 = std::min(info.width_px - 1, static_cast<int>(std::ceil(hi.x())));
  const int y1 = std::min(info.height_px - 1, static_cast<int>(std::ceil(hi.y())));
  const Eigen::Vector2d d = b - a;
  const double len_sq = d.squaredNorm();
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const Eigen::Vector2d p(x + 0.5, y + 0.5);
      const double t = len_sq > 0 ? std::clamp((p - a).dot(d) / len_sq, 0.0, 1.0) : 0.0;
      if ((a + t * d - p).squaredNorm() > r * r) continue;
      uint8_t* px = &rgb[(static_cast<size_t>(y) * info.width_px + x) * 3];
      px[0] = color.r, px[1] = color.g, px[2] = color.b;
    }
}

void RenderImage::fillDisc(const Eigen::Vector3d& centre_map, double radius_m, const Rgb& color) {
  const double per_voxel =
      static_cast<double>(info.scale) / static_cast<double>(info.voxels_per_pixel);
  const double r_px = std::max(1.0, radius_m / resolution_m * per_voxel);
  drawLine(centre_map, centre_map, color, 2.0 * r_px);
}

RenderImage renderTopDownImage(const Map& map, const RenderOptions& options) {
  const RenderLayout layout = internal::renderLayout(map, options);
  const size_t pixels = static_cast<size_t>(layout.grid_w) * layout.grid_h;
  constexpr int32_t kNone = std::numeric_limits<int32_t>::min();
  std::vector<int32_t> top_z(pixels, kNone);
  std::vector<uint8_t> any_free(pixels, 0);
  const OccupancyModel& model = map.model();
  forEachCellIn(map, layout, [&](const VoxelKey& v, const Cell& cell) {
    const CellState s = model.state(cell);
    const size_t p = layout.gridIndex(v);
    if (s == CellState::kOccupied) {
      top_z[p] = std::max(top_z[p], v.z);
    } else if (s == CellState::kFree) {
      any_free[p] = 1;
    }
  });

  RenderInfo info = infoOf(layout);
  int32_t z_lo = std::numeric_limits<int32_t>::max(), z_hi = kNone;
  for (int32_t z : top_z) {
    if (z == kNone) continue;
    z_lo = std::min(z_lo, z);
    z_hi = std::max(z_hi, z);
    ++info.occupied_columns;
  }
  std::vector<Rgb> grid(pixels, options.unknown_color);
  for (size_t p = 0; p < pixels; ++p) {
    if (top_z[p] != kNone) {
      const double t = z_hi > z_lo
                           ? static_cast<double>(int64_t{top_z[p]} - z_lo) / (int64_t{z_hi} - z_lo)
                           : 0.5;
      grid[p] = heightColor(t);
    } else if (any_free[p]) {
      grid[p] = options.free_color;
    }
  }
  if (info.occupied_columns > 0) {
    info.z_min_m = map.centerOf(VoxelKey{0, 0, z_lo}).z();
    info.z_max_m = map.centerOf(VoxelKey{0, 0, z_hi}).z();
  }
  RenderImage image;
  image.info = info;
  image.rgb = internal::scaleToImage(layout, grid);
  image.resolution_m = map.resolution();
  return image;
}

RenderInfo renderSlice(const Map& map, double z_m, const std::string& path_png,
                       const RenderOptions& options) {
  RenderImage image = renderSliceImage(map, z_m, options);
  if (options.legend) appendLegend(image, RenderView::kSlice, options);
  writePng(image, path_png);
  return image.info;
}

RenderImage renderSliceImage(const Map& map, double z_m, const RenderOptions& options) {
  if (!std::isfinite(z_m))
    throw InvalidArgument("render: the slice height must be a finite number of metres");
  RenderLayout layout = internal::renderLayout(map, options);
  layout.lo.z = layout.hi.z = map.keyOf(Eigen::Vector3d(0, 0, z_m)).z;
  const size_t pixels = static_cast<size_t>(layout.grid_w) * layout.grid_h;
  // CellState orders unknown < free < occupied, so a downscaled pixel keeps the maximum.
  std::vector<uint8_t> state(pixels, static_cast<uint8_t>(CellState::kUnknown));
  const OccupancyModel& model = map.model();
  forEachCellIn(map, layout, [&](const VoxelKey& v, const Cell& cell) {
    uint8_t& s = state[layout.gridIndex(v)];
    s = std::max(s, static_cast<uint8_t>(model.state(cell)));
  });

  RenderInfo info = infoOf(layout);
  std::vector<Rgb> grid(pixels, options.unknown_color);
  for (size_t p = 0; p < pixels; ++p) {
    if (state[p] == static_cast<uint8_t>(CellState::kOccupied)) {
      grid[p] = options.occupied_color;
      ++info.occupied_columns;
    } else if (state[p] == static_cast<uint8_t>(CellState::kFree)) {
      grid[p] = options.free_color;
    }
  }
  info.z_min_m = info.z_max_m = map.centerOf(layout.lo).z();
  RenderImage image;
  image.info = info;
  image.rgb = internal::scaleToImage(layout, grid);
  image.resolution_m = map.resolution();
  return image;
}

}  // namespace fragg
