// Writing 8-bit RGB images as PNG, atomically (libpng's simplified API into AtomicFile).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fragg::internal {

/// `rgb` holds width * height * 3 bytes, rows top to bottom. Throws IoError on failure; the
/// target is then left untouched.
void writePngRgb(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb);

}  // namespace fragg::internal
