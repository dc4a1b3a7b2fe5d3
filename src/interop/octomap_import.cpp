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

Map importBinary(const std::string& bytes, const internal::OctomapFileHeader& header,
                 const std::string& path) {
  octomap::OcTree tree(header.resolution);
  std::istringstream in(bytes, std::ios::in | std::ios::binary);
  if (!tree.readBinary(in))
    throw IoError(fmt::format("{}: liboctomap could not read the binary tree", path));
  return internal::mapFromTree(tree, path);
}

Map importFull(const std::string& bytes, const internal::OctomapFileHeader& header,
               const std::string& path) {
  if (header.size == 0) {  // liboctomap would read a root node from no data
    octomap::OcTree empty(header.resolution);
    return internal::mapFromTree(empty, path);
  }
  std::istringstream in(bytes, std::ios::in | std::ios::binary);
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(in));
  if (!tree) throw IoError(fmt::format("{}: liboctomap could not read the tree", path));
  if (auto* t = dynamic_cast<const octomap::OcTree*>(tree.get()))
    return internal::mapFromTree(*t, path);
  if (auto* t = dynamic_cast<const octomap::ColorOcTree*>(tree.get()))
    return internal::mapFromTree(*t, path);
  if (auto* t = dynamic_cast<const octomap::OcTreeStamped*>(tree.get()))
    return internal::mapFromTree(*t, path);
  throw IoError(fmt::format("{}: OctoMap tree type '{}' is not an occupancy tree", path,
                            tree->getTreeType()));
}

}  // namespace

Map fromOcTree(const octomap::OcTree& tree) { return internal::mapFromTree(tree, "OcTree"); }

Map importOctomap(const std::string& path) {
  const std::string bytes = readWholeFile(path);
  const internal::OctomapFileHeader header = internal::parseOctomapHeader(bytes, path);
  internal::checkOctomapData(bytes, header, path);
  if (header.kind == internal::OctomapFileKind::kBinary) return importBinary(bytes, header, path);
  return importFull(bytes, header, path);
}

}  // namespace fragg
