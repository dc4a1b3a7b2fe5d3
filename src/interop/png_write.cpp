#include "png_write.h"

#include <fmt/format.h>
#include <png.h>

#include <cstring>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"

namespace fragg::internal {

void writePngRgb(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb) {
  if (width <= 0 || height <= 0 || rgb.size() != static_cast<size_t>(width) * height * 3)
    throw IoError(fmt::format("cannot write {}: bad image buffer ({} x {}, {} bytes)", path, width,
                              height, rgb.size()));
  AtomicFile file(path);
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = PNG_FORMAT_RGB;
  const int ok = png_image_write_to_stdio(&image, file.stream(), /*convert_to_8bit=*/0, rgb.data(),
                                          /*row_stride=*/0, /*colormap=*/nullptr);
  const std::string message = image.message;
  png_image_free(&image);
  if (!ok) throw IoError(fmt::format("cannot write {}: libpng: {}", path, message));
  file.commit();
}

}  // namespace fragg::internal
