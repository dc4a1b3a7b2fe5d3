// Structural check of OctoMap files before liboctomap parses them. liboctomap trusts its
// input: a truncated or corrupt file makes it recurse on uninitialised bytes. These checks
// walk the node records with bounded depth and byte counts, so that the parser only ever
// sees well-formed data.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace fragg::internal {

enum class OctomapFileKind { kBinary, kFull };  ///< .bt (occupancy bits) | .ot (node data)

struct OctomapFileHeader {
  OctomapFileKind kind = OctomapFileKind::kBinary;
  std::string id;          ///< tree type, e.g. "OcTree"
  uint64_t size = 0;       ///< node count announced by the header
  double resolution = 0;   ///< metres
  size_t data_offset = 0;  ///< first byte of the node data
};

/// Parses the text header as liboctomap does (first line, then "id", "size", "res" and
/// comments up to "data"). Throws IoError naming `path` when it is not a valid header.
OctomapFileHeader parseOctomapHeader(const std::string& bytes, const std::string& path);

/// Bytes of one node's data in a full (.ot) file for tree type `id`; 0 when the type is not
/// an occupancy tree this reader knows.
size_t octomapNodeDataBytes(const std::string& id);

/// Walks the node data after the header and throws IoError naming `path` when it runs past
/// the end of the file, nests deeper than the tree depth (16) or holds a different number
/// of nodes than the header announces.
void checkOctomapData(const std::string& bytes, const OctomapFileHeader& header,
                      const std::string& path);

}  // namespace fragg::internal
