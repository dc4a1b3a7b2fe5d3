// The legend strip below a rendered map (appendLegend): colour swatches, the height ramp and
// what a pixel spans, in the built-in font of glyphs.h.
#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "fragg_map/interop/render.h"
#include "glyphs.h"

namespace fragg {
namespace {

constexpr Rgb kBackground{255, 255, 255};
constexpr Rgb kInk{0, 0, 0};
constexpr int kRampWidth = 64;  ///< glyph pixels (times the legend's scale)

struct LegendItem {
  enum class Kind { kText, kSwatch, kRamp };
  Kind kind = Kind::kText;
  std::string text;  ///< kText
  Rgb color;         ///< kSwatch
};
using LegendLine = std::vector<LegendItem>;

LegendItem text(std::string t) { return {LegendItem::Kind::kText, std::move(t), {}}; }
LegendItem swatch(const Rgb& c) { return {LegendItem::Kind::kSwatch, {}, c}; }
LegendItem ramp() { return {LegendItem::Kind::kRamp, {}, {}}; }

int itemWidthPx(const LegendItem& item, int s) {
  switch (item.kind) {
    case LegendItem::Kind::kText:
      return internal::textWidthPx(item.text, s);
    case LegendItem::Kind::kSwatch:
      return internal::kGlyphHeight * s;
    case LegendItem::Kind::kRamp:
      return kRampWidth * s;
  }
  return 0;
}

/// Space after an item: a swatch or the ramp sits close to its text, texts stand apart.
int gapAfterPx(const LegendItem& item, int s) {
  return (item.kind == LegendItem::Kind::kText ? 10 : 3) * s;
}

int lineWidthPx(const LegendLine& line, int s) {
  int w = 0;
  for (size_t i = 0; i < line.size(); ++i) {
    w += itemWidthPx(line[i], s);
    if (i + 1 < line.size()) w += gapAfterPx(line[i], s);
  }
  return w;
}

/// "1 PX = 1 CELL = 0.05 M" and the like, with the axes.
std::string pixelSpan(const RenderInfo& info, double resolution_m) {
  std::string span;
  if (info.voxels_per_pixel > 1) {
    span = fmt::format("1 PX = {0} X {0} CELLS OF {1:g} M", info.voxels_per_pixel, resolution_m);
  } else if (info.scale > 1) {
    span = fmt::format("1 CELL ({0:g} M) = {1} X {1} PX", resolution_m, info.scale);
  } else {
    span = fmt::format("1 PX = 1 CELL = {:g} M", resolution_m);
  }
  return span + ", X RIGHT, Y UP";
}

std::vector<LegendLine> linesOf(const RenderImage& image, RenderView view,
                                const RenderOptions& options) {
  const RenderInfo& info = image.info;
  std::vector<LegendLine> lines;
  if (view == RenderView::kTop) {
    if (info.occupied_columns == 0) {
      lines.push_back({text("NO OCCUPIED CELL")});
    } else if (info.z_max_m > info.z_min_m) {
      lines.push_back(
          {text(fmt::format("Z {:.2f} M", info.z_min_m)), ramp(),
           text(fmt::format("{:.2f} M: HEIGHT OF THE HIGHEST OCCUPIED CELL", info.z_max_m))});
    } else {
      lines.push_back({swatch(heightColor(0.5)),
                       text(fmt::format("OCCUPIED, ALL AT Z {:.2f} M", info.z_min_m))});
    }
    lines.push_back({swatch(options.free_color), text("FREE ONLY"), swatch(options.unknown_color),
                     text("UNKNOWN")});
    lines.push_back({text(pixelSpan(info, image.resolution_m))});
  } else {
    lines.push_back({swatch(options.occupied_color), text("OCCUPIED"), swatch(options.free_color),
                     text("FREE"), swatch(options.unknown_color), text("UNKNOWN")});
    lines.push_back({text(fmt::format("SLICE AT Z {:.3f} M", info.z_min_m))});
    lines.push_back({text(pixelSpan(info, image.resolution_m))});
  }
  return lines;
}

void fillRect(RenderImage& image, int x0, int y0, int w, int h, const Rgb& c) {
  const int width = image.info.width_px, height = image.info.height_px;
  for (int y = std::max(0, y0); y < std::min(height, y0 + h); ++y)
    for (int x = std::max(0, x0); x < std::min(width, x0 + w); ++x) {
      uint8_t* p = &image.rgb[(static_cast<size_t>(y) * width + x) * 3];
      p[0] = c.r;
      p[1] = c.g;
      p[2] = c.b;
    }
}

}  // namespace

void appendLegend(RenderImage& image, RenderView view, const RenderOptions& options) {
  const std::vector<LegendLine> lines = linesOf(image, view, options);
  const int old_w = image.info.width_px, old_h = image.info.height_px;
  // Text grows with the image: 1 glyph pixel per 400 image pixels of width, 1 to 4.
  const int s = std::clamp(old_w / 400, 1, 4);
  const int pad = 4 * s, line_h = internal::kGlyphHeight * s, line_gap = 4 * s;
  int legend_w = 0;
  for (const LegendLine& line : lines) legend_w = std::max(legend_w, lineWidthPx(line, s));
  const int new_w = std::max(old_w, legend_w + 2 * pad);
  const int strip_h = 2 * pad + static_cast<int>(lines.size()) * line_h +
                      (static_cast<int>(lines.size()) - 1) * line_gap;
  const int new_h = old_h + strip_h;

  std::vector<uint8_t> rgb(static_cast<size_t>(new_w) * new_h * 3, kBackground.r);
  for (int y = 0; y < old_h; ++y)
    std::memcpy(&rgb[static_cast<size_t>(y) * new_w * 3],
                &image.rgb[static_cast<size_t>(y) * old_w * 3], static_cast<size_t>(old_w) * 3);
  image.rgb = std::move(rgb);
  image.info.width_px = new_w;
  image.info.height_px = new_h;
  image.info.legend_height_px = strip_h;

  int y = old_h + pad;
  for (const LegendLine& line : lines) {
    int x = pad;
    for (const LegendItem& item : line) {
      const int w = itemWidthPx(item, s);
      switch (item.kind) {
        case LegendItem::Kind::kText:
          internal::drawText(image, x, y, item.text, kInk, s);
          break;
        case LegendItem::Kind::kSwatch:
          fillRect(image, x, y, w, line_h, kInk);  // a 1-pixel black outline
          fillRect(image, x + 1, y + 1, w - 2, line_h - 2, item.color);
          break;
        case LegendItem::Kind::kRamp:
          for (int i = 0; i < w; ++i)
            fillRect(image, x + i, y, 1, line_h, heightColor(static_cast<double>(i) / (w - 1)));
          break;
      }
      x += w + gapAfterPx(item, s);
    }
    y += line_h + line_gap;
  }
}

}  // namespace fragg
