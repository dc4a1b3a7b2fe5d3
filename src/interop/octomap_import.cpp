// .bt / .ot file -> octomap tree -> Map.
#include <octomap/ColorOcTree.h>
#include <octomap/OcTreeStamped.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "fragg_map/errors.h"
#include "fragg_map/interop/octomap_io.h"
#include "octomap_file_check.h"
#include "octomap_tree_to_map.h"

namespace fragg {
namespace {

std::string readWholeFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw IoError(fmt::format("cannot read {}: no such file", path));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(fmt::format("cannot read {}: not readable", path));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(fmt::format("cannot read {}: I/O error", path));
  return bytes;
}

/// Reads the node data after the header into a `Tree` (liboctomap's readBinaryData or
/// readData, without its header parser and the debug lines it prints).
template <class Tree>
Map readTree(const std::string& bytes, const internal::OctomapFileHeader& header,
             const std::string& path, Backend backend) {
  Tree tree(header.resolution);
  if (header.size > 0) {
    std::istringstream in(bytes, std::ios::in | std::ios::binary);
    in.seekg(static_cast<std::streamoff>(header.data_offset));
    if (header.kind == internal::OctomapFileKind::kBinary) {
      tree.readBinaryData(in);
    } else {
      tree.readData(in);
    }
    if (!in || tree.size() != header.size)
      throw IoError(fmt::format("{}: corrupt OctoMap file: read {} nodes of {}", path, tree.size(),
                                header.size));
  }
  return internal::mapFromTree(tree, path, backend);
}

}  // namespace

Map fromOcTree(const octomap::OcTree& tree, Backend backend) {
  return internal::mapFromTree(tree, "OcTree", backend);
}

Map importOctomap(const std::string& path, Backend backend) {
  const std::string bytes = readWholeFile(path);
  const internal::OctomapFileHeader header = internal::parseOctomapHeader(bytes, path);
  internal::checkOctomapData(bytes, header, path);
  // A .bt holds occupancy bits only, whatever tree type wrote it.
  if (header.kind == internal::OctomapFileKind::kBinary || header.id == "OcTree")
    return readTree<octomap::OcTree>(bytes, header, path, backend);
  if (header.id == "ColorOcTree")
    return readTree<octomap::ColorOcTree>(bytes, header, path, backend);
  if (header.id == "OcTreeStamped")
    return readTree<octomap::OcTreeStamped>(bytes, header, path, backend);
  throw IoError(fmt::format("{}: OctoMap tree type '{}' is not supported", path, header.id));
}

}  // namespace fragg
