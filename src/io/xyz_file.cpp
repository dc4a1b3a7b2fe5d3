// ASCII "x y z [...]" point files (OctoMap's scan.dat, CloudCompare's .xyz, CSV).
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <string>

#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "io_util.h"

namespace fragg {

PointCloud readXyz(const std::string& path) {
  const std::string bytes = internal::readFileBytes(path);
  if (bytes.find('\0') != std::string::npos)
    internal::throwIo(path, "binary data in an ASCII x y z file (compressed? decompress first)");
  PointCloud cloud;
  cloud.points_S.reserve(bytes.size() / 24);
  const char* const data = bytes.c_str();
  size_t pos = 0, line_number = 0;
  while (pos < bytes.size()) {
    size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) end = bytes.size();
    ++line_number;
    size_t cursor = pos;
    auto skip_separators = [&](bool allow_comma) {
      while (cursor < end && (bytes[cursor] == ' ' || bytes[cursor] == '\t' ||
                              bytes[cursor] == '\r' || (allow_comma && bytes[cursor] == ',')))
        ++cursor;
    };
    skip_separators(false);
    if (cursor < end && bytes[cursor] != '#') {
      Eigen::Vector3f p;
      for (int axis = 0; axis < 3; ++axis) {
        if (axis > 0) skip_separators(true);
        char* parsed_end = nullptr;
        const double v = cursor < end ? std::strtod(data + cursor, &parsed_end) : 0.0;
        const bool ok =
            cursor < end && parsed_end != data + cursor && parsed_end <= data + end &&
            (parsed_end == data + end || std::isspace(static_cast<unsigned char>(*parsed_end)) ||
             *parsed_end == ',');
        if (!ok)
          internal::throwIo(path, "line " + std::to_string(line_number) +
                                      ": expected 'x y z', got '" +
                                      bytes.substr(pos, std::min<size_t>(end - pos, 60)) + "'");
        p[axis] = static_cast<float>(v);
        cursor = parsed_end - data;
      }
      cloud.points_S.push_back(p);
    }
    pos = end + 1;
  }
  return cloud;
}

}  // namespace fragg
