#include "octomap_file_check.h"

#include <fmt/format.h>

#include <cmath>
#include <sstream>

#include "fragg_map/errors.h"

namespace fragg::internal {
namespace {

constexpr const char* kBinaryFirstLine = "# Octomap OcTree binary file";
constexpr const char* kFullFirstLine = "# Octomap OcTree file";
constexpr int kTreeDepth = 16;

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

void skipLine(std::istream& s) {
  char c = 0;
  do {
    c = static_cast<char>(s.get());
  } while (s.good() && c != '\n');
}

uint64_t parseSize(const std::string& token, const std::string& path) {
  if (token.empty() || token.find_first_not_of("0123456789") != std::string::npos ||
      token.size() > 18)
    throw IoError(fmt::format("{}: corrupt OctoMap header: bad size '{}'", path, token));
  return std::stoull(token);
}

double parseResolution(const std::string& token, const std::string& path) {
  double res = 0;
  std::istringstream in(token);
  if (!(in >> res) || !std::isfinite(res) || res <= 0)
    throw IoError(fmt::format("{}: corrupt OctoMap header: bad resolution '{}'", path, token));
  return res;
}

/// Cursor over the node data; every read is bounds-checked.
class DataWalker {
 public:
  DataWalker(const std::string& bytes, size_t offset, const std::string& path)
      : bytes_(bytes), pos_(offset), path_(path) {}

  uint8_t byte() {
    need(1);
    return static_cast<uint8_t>(bytes_[pos_++]);
  }
  void skip(size_t n) {
    need(n);
    pos_ += n;
  }
  uint64_t nodes = 0;

  /// .bt: two bytes per inner node, two bits per child (01 occupied leaf, 10 free leaf,
  /// 11 inner node, 00 none); inner children follow depth-first in child order.
  void binaryNode(int depth) {
    const uint8_t lo = byte();
    const uint8_t hi = byte();
    bool inner[8] = {};
    for (int i = 0; i < 8; ++i) {
      const uint8_t bits = static_cast<uint8_t>(((i < 4 ? lo : hi) >> (2 * (i % 4))) & 3);
      if (bits == 0) continue;
      ++nodes;
      inner[i] = bits == 3;
      if (inner[i] && depth + 1 >= kTreeDepth) deeper(depth + 1);
    }
    for (int i = 0; i < 8; ++i)
      if (inner[i]) binaryNode(depth + 1);
  }

  /// .ot: node data, then one byte with a bit per existing child, children depth-first.
  void fullNode(int depth, size_t data_bytes) {
    skip(data_bytes);
    const uint8_t children = byte();
    if (children != 0 && depth >= kTreeDepth) deeper(depth + 1);
    for (int i = 0; i < 8; ++i) {
      if (!(children & (1u << i))) continue;
      ++nodes;
      fullNode(depth + 1, data_bytes);
    }
  }

 private:
  void need(size_t n) const {
    if (bytes_.size() - pos_ < n)
      throw IoError(fmt::format("{}: truncated OctoMap file: node data ends at byte {}", path_,
                                bytes_.size()));
  }
  [[noreturn]] void deeper(int depth) const {
    throw IoError(fmt::format("{}: corrupt OctoMap file: a node at depth {} (the tree has {})",
                              path_, depth, kTreeDepth));
  }

  const std::string& bytes_;
  size_t pos_;
  const std::string& path_;
};

}  // namespace

OctomapFileHeader parseOctomapHeader(const std::string& bytes, const std::string& path) {
  std::istringstream s(bytes);
  std::string line;
  std::getline(s, line);
  OctomapFileHeader h;
  if (startsWith(line, kBinaryFirstLine)) {
    h.kind = OctomapFileKind::kBinary;
  } else if (startsWith(line, kFullFirstLine)) {
    h.kind = OctomapFileKind::kFull;
  } else {
    throw IoError(
        fmt::format("{}: not an OctoMap file (the first line is not '{}' or '{}'; files of OctoMap "
                    "before 1.4 must be converted with convert_octree first)",
                    path, kBinaryFirstLine, kFullFirstLine));
  }
  bool have_res = false;
  std::string token;
  while (s >> token) {
    if (token == "data") {
      skipLine(s);
      if (s.eof()) {
        h.data_offset = bytes.size();
      } else {
        h.data_offset = static_cast<size_t>(s.tellg());
      }
      if (h.id.empty()) h.id = "OcTree";  // liboctomap's .bt reader assumes it as well
      if (h.id == "1") h.id = "OcTree";   // deprecated id
      if (!have_res) throw IoError(path + ": corrupt OctoMap header: no resolution");
      return h;
    }
    if (token[0] == '#') {
      skipLine(s);
    } else if (token == "id") {
      s >> h.id;
    } else if (token == "res") {
      std::string value;
      s >> value;
      h.resolution = parseResolution(value, path);
      have_res = true;
    } else if (token == "size") {
      std::string value;
      s >> value;
      h.size = parseSize(value, path);
    } else {
      skipLine(s);  // liboctomap skips unknown keywords with a warning
    }
  }
  throw IoError(path + ": truncated OctoMap file: the header has no 'data' line");
}

size_t octomapNodeDataBytes(const std::string& id) {
  if (id == "OcTree" || id == "OcTreeStamped") return sizeof(float);
  if (id == "ColorOcTree") return sizeof(float) + 3;  // log-odds + r, g, b
  return 0;
}

void checkOctomapData(const std::string& bytes, const OctomapFileHeader& header,
                      const std::string& path) {
  if (header.size == 0) return;  // an empty tree: liboctomap reads no node data
  DataWalker walker(bytes, header.data_offset, path);
  walker.nodes = 1;  // the root
  if (header.kind == OctomapFileKind::kBinary) {
    walker.binaryNode(0);
  } else {
    const size_t data_bytes = octomapNodeDataBytes(header.id);
    if (data_bytes == 0)
      throw IoError(
          fmt::format("{}: OctoMap tree type '{}' is not supported (OcTree, "
                      "ColorOcTree and OcTreeStamped are)",
                      path, header.id.substr(0, 40)));
    walker.fullNode(0, data_bytes);
  }
  if (walker.nodes != header.size)
    throw IoError(fmt::format("{}: corrupt OctoMap file: {} nodes where the header announces {}",
                              path, walker.nodes, header.size));
}

}  // namespace fragg::internal
