// Binary PGM depth images and their back-projection.
#include "fragg_map/io/depth_image.h"

#include <cctype>
#include <cmath>
#include <limits>
#include <string>

#include "fragg_map/errors.h"
#include "io_util.h"

namespace fragg {
namespace {

// Next header integer of a PGM, skipping whitespace and '#' comments.
uint64_t pgmHeaderValue(const std::string& path, const std::string& bytes, size_t& pos,
                        const char* what) {
  while (pos < bytes.size()) {
    if (std::isspace(static_cast<unsigned char>(bytes[pos]))) {
      ++pos;
    } else if (bytes[pos] == '#') {
      while (pos < bytes.size() && bytes[pos] != '\n') ++pos;
    } else {
      break;
    }
  }
  uint64_t value = 0;
  size_t digits = 0;
  while (pos < bytes.size() && std::isdigit(static_cast<unsigned char>(bytes[pos])) &&
         digits < 10) {
    value = value * 10 + static_cast<uint64_t>(bytes[pos] - '0');
    ++pos;
    ++digits;
  }
  if (digits == 0 || (pos < bytes.size() && std::isdigit(static_cast<unsigned char>(bytes[pos]))))
    internal::throwIo(path, std::string("PGM header: bad or missing ") + what);
  return value;
}

}  // namespace

DepthImage readPgm(const std::string& path) {
  const std::string bytes = internal::readFileBytes(path);
  if (bytes.size() < 2 || bytes[0] != 'P' || bytes[1] != '5')
    internal::throwIo(path, "not a binary PGM file (wrong magic, expected 'P5')");
  size_t pos = 2;
  const uint64_t width = pgmHeaderValue(path, bytes, pos, "width");
  const uint64_t height = pgmHeaderValue(path, bytes, pos, "height");
  const uint64_t maxval = pgmHeaderValue(path, bytes, pos, "maxval");
  if (width == 0 || height == 0 || width > 100000 || height > 100000)
    internal::throwIo(path, "PGM size " + std::to_string(width) + " x " + std::to_string(height) +
                                " is not plausible");
  if (maxval == 0 || maxval > 65535)
    internal::throwIo(path, "PGM maxval " + std::to_string(maxval) + " outside 1..65535");
  if (pos >= bytes.size() || !std::isspace(static_cast<unsigned char>(bytes[pos])))
    internal::throwIo(path, "PGM header: no whitespace after maxval");
  ++pos;  // exactly one whitespace byte before the samples
  const uint64_t sample_bytes = maxval > 255 ? 2 : 1;
  const uint64_t needed = width * height * sample_bytes;
  if (bytes.size() - pos < needed)
    internal::throwIo(path, "truncated PGM data: " + std::to_string(width) + " x " +
                                std::to_string(height) + " needs " + std::to_string(needed) +
                                " bytes, " + std::to_string(bytes.size() - pos) + " present");
  DepthImage image;
  image.width = static_cast<uint32_t>(width);
  image.height = static_cast<uint32_t>(height);
  image.depth.resize(width * height);
  const unsigned char* data = reinterpret_cast<const unsigned char*>(bytes.data()) + pos;
  for (size_t i = 0; i < image.depth.size(); ++i) {
    image.depth[i] =
        sample_bytes == 2 ? static_cast<uint16_t>((data[2 * i] << 8) | data[2 * i + 1]) : data[i];
  }
  return image;
}

DepthIntrinsics readDepthIntrinsics(const std::string& path) {
  const std::vector<internal::TextLine> lines = internal::readDataLines(path);
  if (lines.empty()) internal::throwIo(path, "no 'fx fy cx cy [depth_scale_m]' line");
  const std::vector<std::string> tokens = internal::splitTokens(lines[0].text, true);
  if (tokens.size() != 4 && tokens.size() != 5)
    internal::throwIo(path, "line " + std::to_string(lines[0].number) +
                                ": expected 'fx fy cx cy [depth_scale_m]'");
  double v[5] = {0, 0, 0, 0, 0.001};
  for (size_t i = 0; i < tokens.size(); ++i) {
    if (!internal::parseDouble(tokens[i], &v[i]) || !std::isfinite(v[i]))
      internal::throwIo(path, "'" + tokens[i] + "' is not a finite number");
  }
  if (v[0] <= 0 || v[1] <= 0 || v[4] <= 0)
    internal::throwIo(path, "focal lengths and depth scale must be positive");
  DepthIntrinsics intrinsics;
  intrinsics.fx = v[0];
  intrinsics.fy = v[1];
  intrinsics.cx = v[2];
  intrinsics.cy = v[3];
  intrinsics.depth_scale_m = v[4];
  return intrinsics;
}

PointCloud depthToCloud(const DepthImage& image, const DepthIntrinsics& intrinsics) {
  if (image.depth.size() != size_t{image.width} * image.height)
    throw InvalidArgument("depthToCloud: image says " + std::to_string(image.width) + " x " +
                          std::to_string(image.height) + " but holds " +
                          std::to_string(image.depth.size()) + " samples");
  PointCloud cloud;
  cloud.width = image.width;
  cloud.height = image.height;
  cloud.points_S.resize(size_t{image.width} * image.height);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (uint32_t v = 0; v < image.height; ++v) {
    for (uint32_t u = 0; u < image.width; ++u) {
      const size_t i = size_t{v} * image.width + u;
      const uint16_t raw = image.depth[i];
      if (raw == 0) {
        cloud.points_S[i] = Eigen::Vector3f::Constant(nan);
        continue;
      }
      const double z_m = raw * intrinsics.depth_scale_m;
      cloud.points_S[i] = Eigen::Vector3f(
          static_cast<float>((u - intrinsics.cx) * z_m / intrinsics.fx),
          static_cast<float>((v - intrinsics.cy) * z_m / intrinsics.fy), static_cast<float>(z_m));
    }
  }
  return cloud;
}

}  // namespace fragg
