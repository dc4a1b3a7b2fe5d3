// Frontier cells and viewpoints over a top view.
#include "cli/frontier_drawing.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace fragg::cli {

Rgb clusterColor(uint64_t id) {
  static constexpr std::array<Rgb, 12> kPalette = {{{255, 0, 255},
                                                    {0, 255, 255},
                                                    {255, 140, 0},
                                                    {120, 255, 0},
                                                    {255, 0, 100},
                                                    {0, 120, 255},
                                                    {255, 230, 0},
                                                    {160, 0, 255},
                                                    {0, 255, 140},
                                                    {255, 90, 90},
                                                    {90, 90, 255},
                                                    {200, 255, 90}}};
  return kPalette[id % kPalette.size()];
}

void fadeForOverlay(RenderImage& image) {
  for (uint8_t& c : image.rgb) c = static_cast<uint8_t>((c + 128) / 2);
}

namespace {

bool inside(const std::optional<Eigen::AlignedBox3d>& crop, const Eigen::Vector3d& p) {
  return !crop || crop->contains(p);
}

}  // namespace

void fillCellSquare(RenderImage& image, const Map& map, const VoxelKey& key, const Rgb& color) {
  const double r = map.resolution();
  const Eigen::Vector3d lo(key.x * r, key.y * r, 0.0), hi((key.x + 1) * r, (key.y + 1) * r, 0.0);
  const Eigen::Vector2d a = image.pixelOf(lo), b = image.pixelOf(hi);  // b.y() < a.y()
  const Eigen::Vector2d c = 0.5 * (a + b);
  int x0 = static_cast<int>(std::floor(a.x() + 1e-9)),
      x1 = static_cast<int>(std::ceil(b.x() - 1e-9));
  int y0 = static_cast<int>(std::floor(b.y() + 1e-9)),
      y1 = static_cast<int>(std::ceil(a.y() - 1e-9));
  if (x1 <= x0) x0 = static_cast<int>(std::floor(c.x())), x1 = x0 + 1;
  if (y1 <= y0) y0 = static_cast<int>(std::floor(c.y())), y1 = y0 + 1;
  x0 = std::max(x0, 0), y0 = std::max(y0, 0);
  x1 = std::min(x1, image.info.width_px), y1 = std::min(y1, image.info.height_px);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      uint8_t* px = &image.rgb[(static_cast<size_t>(y) * image.info.width_px + x) * 3];
      px[0] = color.r, px[1] = color.g, px[2] = color.b;
    }
}

FrontierDrawStats drawFrontiers(RenderImage& image, const Map& map, const FrontierResult& result,
                                const std::optional<Eigen::AlignedBox3d>& crop) {
  FrontierDrawStats stats;
  for (const planning::FrontierCluster& cluster : result.clusters) {
    const Rgb color = clusterColor(cluster.id);
    for (const VoxelKey& key : cluster.cells) {
      if (!inside(crop, map.centerOf(key))) continue;
      fillCellSquare(image, map, key, color);
      ++stats.cells_drawn;
    }
  }
  // Marker sizes in pixels, whatever the scale: metres per pixel of this image.
  const double m_per_px = map.resolution() * static_cast<double>(image.info.voxels_per_pixel) /
                          static_cast<double>(image.info.scale);
  for (const std::vector<planning::Viewpoint>& views : result.views)
    for (size_t i = 0; i < views.size(); ++i) {
      const planning::Viewpoint& v = views[i];
      if (!inside(crop, v.position_m)) continue;
      const double radius_px = i == 0 ? 4.0 : 2.5;
      const Eigen::Vector3d tip =
          v.position_m + (4.0 * radius_px * m_per_px) *
                             Eigen::Vector3d(std::cos(v.yaw_rad), std::sin(v.yaw_rad), 0);
      image.drawLine(v.position_m, tip, kViewpointOutline, 4.0);
      image.fillDisc(v.position_m, (radius_px + 1.5) * m_per_px, kViewpointOutline);
      image.drawLine(v.position_m, tip, kViewpointColor, 2.0);
      image.fillDisc(v.position_m, radius_px * m_per_px, kViewpointColor);
      ++stats.viewpoints_drawn;
    }
  return stats;
}

}  // namespace fragg::cli
