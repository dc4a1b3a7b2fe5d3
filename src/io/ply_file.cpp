// PLY reader (ascii, binary little/big endian) and binary little-endian writer.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "io_util.h"

namespace fragg {
namespace {

using internal::ByteCursor;
using internal::throwIo;

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };
enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  size_t data_offset = 0;
};

bool parseType(const std::string& name, PlyType* type) {
  static const struct {
    const char* name;
    PlyType type;
  } kTypes[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& t : kTypes) {
    if (name == t.name) {
      *type = t.type;
      return true;
    }
  }
  return false;
}

size_t typeSize(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

PlyHeader parsePlyHeader(const std::string& path, const std::string& bytes) {
  PlyHeader header;
  size_t pos = 0;
  size_t line_number = 0;
  bool saw_format = false, saw_end = false;
  while (pos < bytes.size()) {
    size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) break;  // a header line always ends with '\n'
    std::string line = bytes.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_number == 1) {
      if (line != "ply")
        throwIo(path, "not a PLY file (wrong magic: first line '" + line.substr(0, 40) + "')");
      continue;
    }
    const std::vector<std::string> tokens = internal::splitTokens(line);
    if (tokens.empty()) continue;
    const std::string& key = tokens[0];
    auto fail = [&](const std::string& problem) {
      throwIo(path, "PLY header line " + std::to_string(line_number) + " ('" + line.substr(0, 60) +
                        "'): " + problem);
    };
    if (key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      if (tokens.size() != 3) fail("expected 'format <type> 1.0'");
      if (tokens[1] == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (tokens[1] == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (tokens[1] == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBigEndian;
      } else {
        fail("unknown format (expected ascii, binary_little_endian, binary_big_endian)");
      }
      if (tokens[2] != "1.0") fail("unsupported version " + tokens[2]);
      saw_format = true;
    } else if (key == "element") {
      PlyElement element;
      if (tokens.size() != 3 || !internal::parseUint64(tokens[2], &element.count))
        fail("expected 'element <name> <count>'");
      element.name = tokens[1];
      header.elements.push_back(element);
    } else if (key == "property") {
      if (header.elements.empty()) fail("property before any element");
      PlyProperty property;
      if (tokens.size() == 5 && tokens[1] == "list") {
        property.is_list = true;
        if (!parseType(tokens[2], &property.count_type) || !parseType(tokens[3], &property.type))
          fail("unknown list type");
        if (property.count_type == PlyType::kFloat32 || property.count_type == PlyType::kFloat64)
          fail("list count type must be an integer type");
        property.name = tokens[4];
      } else if (tokens.size() == 3) {
        if (!parseType(tokens[1], &property.type)) fail("unknown type '" + tokens[1] + "'");
        property.name = tokens[2];
      } else {
        fail("expected 'property <type> <name>' or 'property list <type> <type> <name>'");
      }
      header.elements.back().properties.push_back(property);
    } else if (key == "end_header") {
      saw_end = true;
      break;
    } else {
      fail("unknown keyword");
    }
  }
  if (line_number == 0) {
    throwIo(path, bytes.empty() ? std::string("empty file, not a PLY file")
                                : std::string("not a PLY file (no header line)"));
  }
  if (!saw_end) throwIo(path, "PLY header has no end_header (truncated or corrupted header)");
  if (!saw_format) throwIo(path, "PLY header has no format line");
  header.data_offset = pos;
  return header;
}

// Binary scalar as double.
double readBinaryScalar(ByteCursor& cursor, PlyType type, bool big_endian, const char* what) {
  switch (type) {
    case PlyType::kInt8:
      return cursor.read<int8_t>(what);
    case PlyType::kUint8:
      return cursor.read<uint8_t>(what);
    case PlyType::kInt16:
      return cursor.read<int16_t>(what, big_endian);
    case PlyType::kUint16:
      return cursor.read<uint16_t>(what, big_endian);
    case PlyType::kInt32:
      return cursor.read<int32_t>(what, big_endian);
    case PlyType::kUint32:
      return cursor.read<uint32_t>(what, big_endian);
    case PlyType::kFloat32:
      return cursor.read<float>(what, big_endian);
    case PlyType::kFloat64:
      return cursor.read<double>(what, big_endian);
  }
  return 0.0;
}

// Index of x, y, z in the vertex element; throws when one is missing or a list.
void findPlyXyz(const std::string& path, const PlyElement& vertex, int xyz[3]) {
  static const char* const kNames[3] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    xyz[axis] = -1;
    for (size_t i = 0; i < vertex.properties.size(); ++i) {
      if (vertex.properties[i].name != kNames[axis]) continue;
      if (vertex.properties[i].is_list)
        throwIo(path, std::string("PLY vertex property ") + kNames[axis] + " is a list");
      xyz[axis] = static_cast<int>(i);
    }
    if (xyz[axis] < 0)
      throwIo(path, std::string("PLY vertex element has no ") + kNames[axis] + " property");
  }
}

Eigen::Vector3f noReturnToNan(const Eigen::Vector3f& p) {
  if (p.x() == 0.0f && p.y() == 0.0f && p.z() == 0.0f)
    return Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  return p;
}

void readBinaryBody(const std::string& path, const std::string& bytes, const PlyHeader& header,
                    std::vector<Eigen::Vector3f>& points) {
  const bool big_endian = header.format == PlyFormat::kBinaryBigEndian;
  ByteCursor cursor(bytes.data(), bytes.size(), path);
  cursor.seek(header.data_offset);
  for (const PlyElement& element : header.elements) {
    const bool is_vertex = element.name == "vertex";
    int xyz[3] = {-1, -1, -1};
    if (is_vertex) findPlyXyz(path, element, xyz);
    // Fixed-size records can be checked against the file size before allocating.
    size_t record_bytes = 0;
    bool fixed = true;
    for (const PlyProperty& p : element.properties) {
      fixed = fixed && !p.is_list;
      record_bytes += typeSize(p.type);
    }
    if (fixed && record_bytes > 0 && element.count > cursor.remaining() / record_bytes) {
      throwIo(path, "truncated PLY binary data: element " + element.name + " needs " +
                        std::to_string(element.count) + " x " + std::to_string(record_bytes) +
                        " bytes, " + std::to_string(cursor.remaining()) + " left");
    }
    if (!is_vertex && fixed) {
      cursor.skip(element.count * record_bytes, "PLY element");
      continue;
    }
    if (is_vertex) points.reserve(std::min<uint64_t>(element.count, cursor.remaining() / 3));
    for (uint64_t i = 0; i < element.count; ++i) {
      Eigen::Vector3f p = Eigen::Vector3f::Zero();
      for (size_t k = 0; k < element.properties.size(); ++k) {
        const PlyProperty& property = element.properties[k];
        if (property.is_list) {
          const double n = readBinaryScalar(cursor, property.count_type, big_endian, "PLY list");
          if (!(n >= 0)) throwIo(path, "PLY list with a negative length in " + element.name);
          cursor.skip(static_cast<uint64_t>(n) * typeSize(property.type), "PLY list");
          continue;
        }
        const double v = readBinaryScalar(cursor, property.type, big_endian, "PLY vertex data");
        for (int axis = 0; axis < 3; ++axis)
          if (static_cast<int>(k) == xyz[axis]) p[axis] = static_cast<float>(v);
      }
      if (is_vertex) points.push_back(noReturnToNan(p));
    }
    if (is_vertex) return;  // what follows the vertices is not needed
  }
}

void readAsciiBody(const std::string& path, const std::string& bytes, const PlyHeader& header,
                   std::vector<Eigen::Vector3f>& points) {
  size_t pos = header.data_offset;
  const char* const data = bytes.c_str();
  // Next whitespace-separated token as a double; throws at the end of the data.
  auto next_value = [&](const std::string& element, uint64_t index) {
    while (pos < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
    if (pos >= bytes.size())
      throwIo(path, "truncated PLY ascii data in " + element + " " + std::to_string(index));
    const size_t start = pos;
    while (pos < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
    char* end = nullptr;
    const double v = std::strtod(data + start, &end);
    if (end != data + pos)
      throwIo(path, "PLY ascii " + element + " " + std::to_string(index) + ": '" +
                        bytes.substr(start, std::min<size_t>(pos - start, 32)) +
                        "' is not a number");
    return v;
  };
  for (const PlyElement& element : header.elements) {
    const bool is_vertex = element.name == "vertex";
    int xyz[3] = {-1, -1, -1};
    if (is_vertex) {
      findPlyXyz(path, element, xyz);
      points.reserve(std::min<uint64_t>(element.count, (bytes.size() - pos) / 6));
    }
    for (uint64_t i = 0; i < element.count; ++i) {
      Eigen::Vector3f p = Eigen::Vector3f::Zero();
      for (size_t k = 0; k < element.properties.size(); ++k) {
        const PlyProperty& property = element.properties[k];
        if (property.is_list) {
          const double n = next_value(element.name, i);
          if (!(n >= 0) || n != std::floor(n))
            throwIo(path,
                    "PLY ascii " + element.name + " " + std::to_string(i) + ": bad list length");
          for (uint64_t j = 0; j < static_cast<uint64_t>(n); ++j) next_value(element.name, i);
          continue;
        }
        const double v = next_value(element.name, i);
        for (int axis = 0; axis < 3; ++axis)
          if (static_cast<int>(k) == xyz[axis]) p[axis] = static_cast<float>(v);
      }
      if (is_vertex) points.push_back(noReturnToNan(p));
    }
    if (is_vertex) return;
  }
}

}  // namespace

PointCloud readPly(const std::string& path) {
  const std::string bytes = internal::readFileBytes(path);
  const PlyHeader header = parsePlyHeader(path, bytes);
  bool has_vertex = false;
  for (const PlyElement& element : header.elements) has_vertex |= element.name == "vertex";
  if (!has_vertex) throwIo(path, "PLY file has no vertex element");
  PointCloud cloud;
  if (header.format == PlyFormat::kAscii)
    readAsciiBody(path, bytes, header, cloud.points_S);
  else
    readBinaryBody(path, bytes, header, cloud.points_S);
  return cloud;
}

void writePly(const std::string& path, const std::vector<Eigen::Vector3f>& points) {
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment written by fragg_map\n"
         << "element vertex " << points.size() << "\n"
         << "property float x\nproperty float y\nproperty float z\nend_header\n";
  AtomicFile file(path);
  file.write(header.str());
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "Vector3f must be packed");
  file.write(points.data(), points.size() * sizeof(Eigen::Vector3f));
  file.commit();
}

}  // namespace fragg
