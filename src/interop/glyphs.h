// Text in rendered images (the legend of fragg_map render): a built-in 5 x 7 pixel font of
// capital letters, digits and a little punctuation, each glyph drawn as filled squares of
// `scale` pixels.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "fragg_map/interop/render.h"

namespace fragg::internal {

inline constexpr int kGlyphWidth = 5;    ///< glyph columns
inline constexpr int kGlyphHeight = 7;   ///< glyph rows
inline constexpr int kGlyphAdvance = 6;  ///< columns from one glyph to the next (1 of space)

/// The rows of a character's glyph, top to bottom; bit 4 is the leftmost column. Lower-case
/// letters take their capital's glyph; a character without a glyph takes '?'.
[[nodiscard]] std::array<uint8_t, kGlyphHeight> glyphRows(char c);

/// Width in pixels of `text` drawn at `scale` (no trailing gap); 0 for an empty text.
[[nodiscard]] int textWidthPx(std::string_view text, int scale);

/// Draws `text` with its top-left corner at pixel (x_px, y_px) of `image`, each glyph pixel a
/// `scale` x `scale` square of `color`; pixels outside the image are skipped.
void drawText(RenderImage& image, int x_px, int y_px, std::string_view text, const Rgb& color,
              int scale);

}  // namespace fragg::internal
