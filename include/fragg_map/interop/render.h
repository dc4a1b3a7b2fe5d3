// PNG images of a map: a top-down height image and horizontal slices.
//
// Image axes: x grows to the right, y grows upwards (north up); one voxel is `scale` pixels
// wide. The image covers the map's observed x/y bounds, or the crop box when one is given.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fragg_map/map.h"

namespace fragg {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
  bool operator!=(const Rgb& o) const { return !(*this == o); }
};

struct RenderOptions {
  int scale = 1;  ///< pixels per voxel edge, >= 1
  /// Only cells inside the box (metres, map frame) are drawn and the image covers its x/y
  /// extent; without it the image covers the observed bounds (and all heights).
  std::optional<Eigen::AlignedBox3d> crop;
  int max_side_px = 4096;  ///< longest image side allowed
  /// When the image would exceed max_side_px: lower the scale, and when one pixel per voxel
  /// is still too many, draw several voxels per pixel (a pixel shows the highest occupied /
  /// any occupied, else any free cell of its voxels) instead of throwing InvalidArgument.
  bool auto_downscale = true;
  Rgb free_color{200, 200, 200};    ///< free (and no occupied) cells: light grey
  Rgb unknown_color{24, 24, 24};    ///< never observed or inside the unknown band: near black
  Rgb occupied_color{230, 60, 30};  ///< slice view; the top view colours by height instead
  /// A legend strip below the map (renderTopDown, renderSlice): what each colour means, the
  /// heights at the ends of the colour ramp, what a pixel spans. `fragg_map render` draws it.
  bool legend = false;
};

/// What was drawn.
struct RenderInfo {
  int width_px = 0;
  int height_px = 0;
  int64_t voxels_per_pixel = 1;     ///< > 1 when the image was downscaled (per axis)
  int scale = 1;                    ///< pixels per voxel edge (per group of voxels when downscaled)
  VoxelKey min_key, max_key;        ///< inclusive voxel range drawn (x, y; z of the cells counted)
  size_t occupied_columns = 0;      ///< pixels showing an occupied cell
  double z_min_m = 0, z_max_m = 0;  ///< top view: heights at the ends of the colour ramp
  /// The map's part of the image, from its top-left corner: width_px x height_px without a
  /// legend; with one (appendLegend) the legend's rows lie below, its padding to the right.
  int map_width_px = 0, map_height_px = 0;
  int legend_height_px = 0;  ///< rows of the legend strip at the bottom (0: none)
};

/// A rendered image in memory: packed RGB rows, top to bottom, and where map points fall on it
/// (for drawing over the map: fragg_map collide --png).
struct RenderImage {
  RenderInfo info;
  std::vector<uint8_t> rgb;  ///< width_px * height_px * 3
  double resolution_m = 0.0;

  /// Image position (pixels, x right, y down, fractional) of a map point's x and y.
  Eigen::Vector2d pixelOf(const Eigen::Vector3d& p_map) const;
  /// A line between two map points' image positions, `width_px` wide (clipped to the image).
  void drawLine(const Eigen::Vector3d& a_map, const Eigen::Vector3d& b_map, const Rgb& color,
                double width_px = 1.0);
  /// A filled disc about a map point's image position, radius in metres (at least 1 px).
  void fillDisc(const Eigen::Vector3d& centre_map, double radius_m, const Rgb& color);
};

/// Colour ramp for heights, t in [0, 1] (clamped): blue, cyan, green, yellow, red.
Rgb heightColor(double t);

/// Top-down height image: a pixel whose column holds an occupied cell takes the ramp colour
/// of the highest one (the ramp spans the lowest to the highest such top cell; a single
/// height takes the middle), a column with free cells only is free_color, one with neither
/// is unknown_color. With options.legend, a legend below (appendLegend). Writes `path_png`
/// atomically. Throws InvalidArgument for bad options or
/// an empty map without a crop box, IoError when the file cannot be written.
RenderInfo renderTopDown(const Map& map, const std::string& path_png,
                         const RenderOptions& options = RenderOptions());
/// The same image in memory (no legend: appendLegend adds one).
RenderImage renderTopDownImage(const Map& map, const RenderOptions& options = RenderOptions());
/// Writes an image as PNG, atomically (IoError when it cannot).
void writePng(const RenderImage& image, const std::string& path_png);

/// The kind of image a legend describes.
enum class RenderView { kTop, kSlice };

/// Appends a legend strip below `image` (rendered as `view` with `options`): white, black
/// capitals of a built-in 5 x 7 font (scaled with the image), a swatch per colour with its
/// meaning, the height ramp with its end heights (top view; "no occupied cell" without one),
/// the slice height (slice view), what a pixel spans and the axes. Where the legend is wider
/// than the map the image is widened with the legend's white; the map's pixels keep their
/// positions (pixelOf). Updates info's width_px, height_px and legend_height_px.
void appendLegend(RenderImage& image, RenderView view, const RenderOptions& options);

/// Horizontal slice through the voxel layer that holds height `z_m`: occupied_color,
/// free_color and unknown_color per cell state (map's own occupancy model). Same image
/// geometry and errors as renderTopDown; the crop box's z extent is ignored.
RenderInfo renderSlice(const Map& map, double z_m, const std::string& path_png,
                       const RenderOptions& options = RenderOptions());
/// The same slice in memory (no legend: appendLegend adds one).
RenderImage renderSliceImage(const Map& map, double z_m,
                             const RenderOptions& options = RenderOptions());

}  // namespace fragg
