// PCD v0.7 reader (ascii, binary, binary_compressed) and binary writer.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "io_util.h"
#include "lzf.h"

namespace fragg {
namespace {

using internal::ByteCursor;
using internal::throwIo;

enum class PcdEncoding { kAscii, kBinary, kBinaryCompressed };

struct PcdField {
  std::string name;
  uint64_t size = 0;   // bytes per element
  char type = 'F';     // F, I or U
  uint64_t count = 1;  // elements per point
};

struct PcdHeader {
  std::vector<PcdField> fields;
  uint64_t width = 0;
  uint64_t height = 1;
  uint64_t points = 0;
  bool has_width = false;
  bool has_points = false;
  Eigen::Isometry3d T_file_sensor = Eigen::Isometry3d::Identity();
  bool has_viewpoint_rotation_or_offset = false;
  PcdEncoding encoding = PcdEncoding::kAscii;
  size_t data_offset = 0;  // first byte after the DATA line
};

// Where x, y and z live in a point record (byte offsets for binary, token indices for ascii).
struct XyzLayout {
  int field[3] = {-1, -1, -1};
  uint64_t byte_offset[3] = {0, 0, 0};
  uint64_t token_index[3] = {0, 0, 0};
  uint64_t point_bytes = 0;  // binary record size
  uint64_t tokens = 0;       // ascii tokens per point
};

const char* const kAxisNames[3] = {"x", "y", "z"};

bool knownSize(char type, uint64_t size) {
  if (type == 'F') return size == 4 || size == 8;
  if (type == 'I' || type == 'U') return size == 1 || size == 2 || size == 4 || size == 8;
  return false;
}

PcdHeader parseHeader(const std::string& path, const std::string& bytes) {
  if (bytes.empty()) throwIo(path, "empty file, not a PCD file");
  PcdHeader header;
  std::vector<std::string> names, sizes, types, counts;
  bool saw_fields = false, saw_data = false;
  size_t pos = 0;
  size_t line_number = 0;
  while (pos < bytes.size() && !saw_data) {
    size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) end = bytes.size();
    std::string line = bytes.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string> tokens = internal::splitTokens(line);
    if (tokens.empty() || tokens[0][0] == '#') continue;
    const std::string& key = tokens[0];
    const std::vector<std::string> values(tokens.begin() + 1, tokens.end());
    auto fail = [&](const std::string& problem) {
      throwIo(path,
              "PCD header line " + std::to_string(line_number) + " (" + key + "): " + problem);
    };
    auto single_uint = [&]() {
      uint64_t v = 0;
      if (values.size() != 1 || !internal::parseUint64(values[0], &v))
        fail("expected one non-negative integer");
      return v;
    };
    if (key == "VERSION") {
      // 0.5, 0.6, 0.7 and ".7" all share the layout this reader understands.
    } else if (key == "FIELDS" || key == "COLUMNS") {
      names = values;
      saw_fields = true;
    } else if (key == "SIZE") {
      sizes = values;
    } else if (key == "TYPE") {
      types = values;
    } else if (key == "COUNT") {
      counts = values;
    } else if (key == "WIDTH") {
      header.width = single_uint();
      header.has_width = true;
    } else if (key == "HEIGHT") {
      header.height = single_uint();
    } else if (key == "POINTS") {
      header.points = single_uint();
      header.has_points = true;
    } else if (key == "VIEWPOINT") {
      double v[7];
      if (values.size() != 7) fail("expected 7 numbers: tx ty tz qw qx qy qz");
      for (int i = 0; i < 7; ++i)
        if (!internal::parseDouble(values[i], &v[i]) || !std::isfinite(v[i]))
          fail("'" + values[i] + "' is not a finite number");
      const Eigen::Quaterniond q =
          internal::checkedQuaternion(v[4], v[5], v[6], v[3], path + ": PCD VIEWPOINT");
      header.T_file_sensor = Eigen::Isometry3d::Identity();
      header.T_file_sensor.linear() = q.toRotationMatrix();
      header.T_file_sensor.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
      header.has_viewpoint_rotation_or_offset =
          v[0] != 0.0 || v[1] != 0.0 || v[2] != 0.0 || !(v[3] == 1.0 || v[3] == -1.0);
    } else if (key == "DATA") {
      if (values.size() != 1) fail("expected ascii, binary or binary_compressed");
      if (values[0] == "ascii") {
        header.encoding = PcdEncoding::kAscii;
      } else if (values[0] == "binary") {
        header.encoding = PcdEncoding::kBinary;
      } else if (values[0] == "binary_compressed") {
        header.encoding = PcdEncoding::kBinaryCompressed;
      } else {
        fail("unknown encoding '" + values[0] + "' (expected ascii, binary, binary_compressed)");
      }
      saw_data = true;
      header.data_offset = std::min(pos, bytes.size());
    } else if (line_number == 1 || !saw_fields) {
      throwIo(path, "not a PCD file (wrong magic: the first header line is '" + line.substr(0, 40) +
                        "')");
    } else {
      fail("unknown header keyword");
    }
  }
  if (!saw_fields) throwIo(path, "not a PCD file (no FIELDS line in the header)");
  if (!saw_data) throwIo(path, "PCD header has no DATA line (truncated or corrupted header)");

  const size_t n = names.size();
  if (sizes.size() != n || types.size() != n || (!counts.empty() && counts.size() != n)) {
    throwIo(path, "PCD header: FIELDS has " + std::to_string(n) + " entries but SIZE has " +
                      std::to_string(sizes.size()) + ", TYPE " + std::to_string(types.size()) +
                      ", COUNT " + std::to_string(counts.size()));
  }
  for (size_t i = 0; i < n; ++i) {
    PcdField field;
    field.name = names[i];
    if (!internal::parseUint64(sizes[i], &field.size))
      throwIo(path, "PCD header: SIZE '" + sizes[i] + "' of field " + names[i] + " is invalid");
    if (types[i].size() != 1 || !knownSize(types[i][0], field.size))
      throwIo(path, "PCD header: field " + names[i] + " has TYPE '" + types[i] + "' SIZE " +
                        sizes[i] + ", expected F 4|8, I or U 1|2|4|8");
    field.type = types[i][0];
    if (!counts.empty() && (!internal::parseUint64(counts[i], &field.count) || field.count == 0 ||
                            field.count > (1u << 20)))
      throwIo(path, "PCD header: COUNT '" + counts[i] + "' of field " + names[i] + " is invalid");
    header.fields.push_back(field);
  }
  if (!header.has_width) throwIo(path, "PCD header has no WIDTH");
  if (header.height == 0 && header.width != 0) throwIo(path, "PCD header: HEIGHT is 0");
  const uint64_t product = header.width * header.height;
  if (header.height != 0 && product / header.height != header.width)
    throwIo(path, "PCD header: WIDTH x HEIGHT overflows");
  if (!header.has_points) header.points = product;
  if (header.points != product)
    throwIo(path, "PCD header: POINTS " + std::to_string(header.points) + " != WIDTH " +
                      std::to_string(header.width) + " x HEIGHT " + std::to_string(header.height));
  return header;
}

// binary_compressed leaves out PCL's "_" padding fields; the other encodings keep them.
XyzLayout findXyz(const std::string& path, const PcdHeader& header, bool skip_padding) {
  XyzLayout layout;
  for (size_t i = 0; i < header.fields.size(); ++i) {
    const PcdField& f = header.fields[i];
    if (skip_padding && f.name == "_") continue;
    for (int axis = 0; axis < 3; ++axis) {
      if (f.name != kAxisNames[axis]) continue;
      if (layout.field[axis] >= 0) throwIo(path, "PCD header: field " + f.name + " repeated");
      if (f.type != 'F' || f.count != 1)
        throwIo(path, "PCD field " + f.name + " must be F 4 or F 8 with COUNT 1 (has TYPE " +
                          std::string(1, f.type) + " SIZE " + std::to_string(f.size) + " COUNT " +
                          std::to_string(f.count) + ")");
      layout.field[axis] = static_cast<int>(i);
      layout.byte_offset[axis] = layout.point_bytes;
      layout.token_index[axis] = layout.tokens;
    }
    layout.point_bytes += f.size * f.count;
    layout.tokens += f.count;
  }
  for (int axis = 0; axis < 3; ++axis)
    if (layout.field[axis] < 0)
      throwIo(path, std::string("PCD file has no ") + kAxisNames[axis] + " field");
  return layout;
}

float loadFloat(const char* p, uint64_t size) {
  if (size == 4) {
    float v;
    std::memcpy(&v, p, 4);
    return v;
  }
  double v;
  std::memcpy(&v, p, 8);
  return static_cast<float>(v);
}

void readAscii(const std::string& path, const std::string& bytes, const PcdHeader& header,
               std::vector<Eigen::Vector3f>& points) {
  const XyzLayout layout = findXyz(path, header, false);
  size_t pos = header.data_offset;
  uint64_t read = 0;
  const char* const data = bytes.c_str();  // NUL-terminated: strtod stops there
  while (read < header.points) {
    // Skip blank lines.
    while (pos < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
    if (pos >= bytes.size()) break;
    size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) end = bytes.size();
    Eigen::Vector3f p;
    uint64_t token = 0;
    size_t cursor = pos;
    int found = 0;
    while (cursor < end && found < 3) {
      while (cursor < end &&
             (bytes[cursor] == ' ' || bytes[cursor] == '\t' || bytes[cursor] == '\r'))
        ++cursor;
      if (cursor >= end) break;
      const size_t token_start = cursor;
      while (cursor < end && !std::isspace(static_cast<unsigned char>(bytes[cursor]))) ++cursor;
      for (int axis = 0; axis < 3; ++axis) {
        if (layout.token_index[axis] != token) continue;
        char* parsed_end = nullptr;
        const double v = std::strtod(data + token_start, &parsed_end);
        if (parsed_end != data + cursor)
          throwIo(path, "PCD ascii point " + std::to_string(read) + ": '" +
                            bytes.substr(token_start, std::min<size_t>(cursor - token_start, 32)) +
                            "' is not a number");
        p[axis] = static_cast<float>(v);
        ++found;
      }
      ++token;
    }
    if (found < 3)
      throwIo(path, "PCD ascii point " + std::to_string(read) + " has too few values (needs " +
                        std::to_string(layout.tokens) + ")");
    points.push_back(p);
    ++read;
    pos = end;
  }
  if (read < header.points)
    throwIo(path, "truncated PCD ascii data: " + std::to_string(read) + " of " +
                      std::to_string(header.points) + " points");
}

void readBinary(const std::string& path, const std::string& bytes, const PcdHeader& header,
                std::vector<Eigen::Vector3f>& points) {
  const XyzLayout layout = findXyz(path, header, false);
  const uint64_t available = bytes.size() - header.data_offset;
  if (layout.point_bytes == 0 || header.points > available / layout.point_bytes)
    throwIo(path, "truncated PCD binary data: " + std::to_string(header.points) + " points of " +
                      std::to_string(layout.point_bytes) + " bytes do not fit in the " +
                      std::to_string(available) + " bytes after the header");
  const char* record = bytes.data() + header.data_offset;
  points.resize(header.points);
  for (uint64_t i = 0; i < header.points; ++i, record += layout.point_bytes) {
    for (int axis = 0; axis < 3; ++axis) {
      const PcdField& f = header.fields[layout.field[axis]];
      points[i][axis] = loadFloat(record + layout.byte_offset[axis], f.size);
    }
  }
}

void readBinaryCompressed(const std::string& path, const std::string& bytes,
                          const PcdHeader& header, std::vector<Eigen::Vector3f>& points) {
  const XyzLayout layout = findXyz(path, header, true);
  ByteCursor cursor(bytes.data(), bytes.size(), path);
  cursor.seek(header.data_offset);
  const uint32_t compressed_size = cursor.read<uint32_t>("PCD binary_compressed size header");
  const uint32_t uncompressed_size = cursor.read<uint32_t>("PCD binary_compressed size header");
  if (header.points > UINT64_MAX / layout.point_bytes)
    throwIo(path, "PCD header: POINTS x point size overflows");
  const uint64_t expected = header.points * layout.point_bytes;
  if (uncompressed_size != expected)
    throwIo(path, "PCD binary_compressed: uncompressed size " + std::to_string(uncompressed_size) +
                      " != " + std::to_string(header.points) + " points x " +
                      std::to_string(layout.point_bytes) + " bytes");
  cursor.require(compressed_size, "PCD binary_compressed data");
  // An LZF back reference of 3 bytes expands to at most 264: reject absurd ratios before
  // allocating (a corrupted size field must not allocate gigabytes).
  if (uncompressed_size > 88ull * compressed_size + 64)
    throwIo(path, "PCD binary_compressed: uncompressed size " + std::to_string(uncompressed_size) +
                      " impossible for " + std::to_string(compressed_size) + " compressed bytes");
  std::vector<unsigned char> raw(uncompressed_size);
  if (!internal::lzfDecompress(reinterpret_cast<const unsigned char*>(cursor.current()),
                               compressed_size, raw.data(), raw.size()))
    throwIo(path, "PCD binary_compressed: corrupted LZF data");
  // Field-major layout: all points' first field, then all points' second field, ...
  points.resize(header.points);
  for (int axis = 0; axis < 3; ++axis) {
    const PcdField& f = header.fields[layout.field[axis]];
    const char* column =
        reinterpret_cast<const char*>(raw.data()) + layout.byte_offset[axis] * header.points;
    for (uint64_t i = 0; i < header.points; ++i)
      points[i][axis] = loadFloat(column + i * f.size, f.size);
  }
}

void writePcdData(const std::string& path, const std::vector<Eigen::Vector3f>& points,
                  uint64_t width, uint64_t height) {
  std::ostringstream header;
  header << "# .PCD v0.7 - Point Cloud Data file format (fragg_map)\n"
         << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
         << "WIDTH " << width << "\nHEIGHT " << height << "\nVIEWPOINT 0 0 0 1 0 0 0\n"
         << "POINTS " << points.size() << "\nDATA binary\n";
  AtomicFile file(path);
  file.write(header.str());
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "Vector3f must be packed");
  file.write(points.data(), points.size() * sizeof(Eigen::Vector3f));
  file.commit();
}

}  // namespace

PointCloud readPcd(const std::string& path, Eigen::Isometry3d* T_file_sensor) {
  const std::string bytes = internal::readFileBytes(path);
  const PcdHeader header = parseHeader(path, bytes);
  PointCloud cloud;
  switch (header.encoding) {
    case PcdEncoding::kAscii:
      cloud.points_S.reserve(std::min<uint64_t>(header.points, bytes.size() / 2));
      readAscii(path, bytes, header, cloud.points_S);
      break;
    case PcdEncoding::kBinary:
      readBinary(path, bytes, header, cloud.points_S);
      break;
    case PcdEncoding::kBinaryCompressed:
      readBinaryCompressed(path, bytes, header, cloud.points_S);
      break;
  }
  if (header.height > 1) {
    cloud.width = static_cast<uint32_t>(header.width);
    cloud.height = static_cast<uint32_t>(header.height);
    if (cloud.width != header.width || cloud.height != header.height)
      throwIo(path, "PCD organised size " + std::to_string(header.width) + " x " +
                        std::to_string(header.height) + " is too large");
  }
  if (header.has_viewpoint_rotation_or_offset) {
    const Eigen::Isometry3f T_sensor_file = header.T_file_sensor.inverse().cast<float>();
    for (Eigen::Vector3f& p : cloud.points_S) p = T_sensor_file * p;  // NaN stays NaN
  }
  if (T_file_sensor) *T_file_sensor = header.T_file_sensor;
  return cloud;
}

void writePcd(const std::string& path, const std::vector<Eigen::Vector3f>& points) {
  writePcdData(path, points, points.size(), 1);
}

void writePcd(const std::string& path, const PointCloud& cloud) {
  if (cloud.height > 1 && !cloud.organised())
    throw InvalidArgument("writePcd " + path + ": cloud says " + std::to_string(cloud.width) +
                          " x " + std::to_string(cloud.height) + " but has " +
                          std::to_string(cloud.size()) + " points");
  if (cloud.organised())
    writePcdData(path, cloud.points_S, cloud.width, cloud.height);
  else
    writePcdData(path, cloud.points_S, cloud.size(), 1);
}

}  // namespace fragg
