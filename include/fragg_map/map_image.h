// A map as it will be saved, taken apart from the map: Map::image() copies what the .fgm file
// needs (header, blocks, region, kept scans) while the caller holds the map's read lock;
// writeMapImage() compresses and writes it later, with the lock released. What the server's
// autosave does, so that insertion waits for the copy only, not for compression and disk.
//
//   fragg::MapImage image;
//   { auto state = shared.read(); image = state->map.image(); }  // a memory copy
//   fragg::writeMapImage(image, "autosave.fgm");                  // same bytes as Map::save
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fragg_map/cell.h"
#include "fragg_map/key.h"

namespace fragg {

struct MapImage {
  std::vector<uint8_t> header;  ///< magic to scan count (map_file_format.h)
  std::vector<BlockKey> keys;   ///< sorted as in the file
  std::vector<Block> blocks;    ///< copies, in the order of `keys`
  std::vector<uint8_t> tail;    ///< region and kept scans, encoded
  bool empty() const { return header.empty(); }
  /// The memory the image holds.
  size_t bytes() const {
    return header.size() + tail.size() + keys.size() * sizeof(BlockKey) +
           blocks.size() * sizeof(Block);
  }
};

/// Writes `image` as a .fgm file, atomically (atomic_file.h: temporary file, fsync, rename),
/// byte for byte what Map::save writes for the same map. Throws IoError (the previous file at
/// `path`, if any, stays) and InvalidArgument for an empty image.
void writeMapImage(const MapImage& image, const std::string& path);

}  // namespace fragg
