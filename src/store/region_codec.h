// A region record (store format 2): the blocks of one region of 4x4x4 blocks, each encoded on
// its own by BlockCodec (a uniform block is one value, 9 bytes; the others zstd frames with a
// checksum), so that one block reads without decoding the others:
//   'R', kRegionBits, count (uint16), then count entries of (local index uint16, size uint32)
//   in local-index order, then the blocks' encodings in the same order.
// A local index is the block's place in its region: x | y << bits | z << 2 bits. Format 1's
// block records begin with 'U' or a zstd frame's magic, never with 'R'.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "block_codec.h"
#include "fragg_map/page_store.h"

namespace fragg {

/// A parsed region record: where each block's encoding lies (views into the record's bytes).
class RegionRecordView {
 public:
  /// IoError naming `where` when the bytes are not a well-formed region record.
  RegionRecordView(const void* data, size_t size, const BlockKey& region, const std::string& where);
  size_t count() const { return entries_.size(); }
  /// The i-th block's key and encoding.
  BlockKey key(size_t i) const;
  std::pair<const void*, size_t> encoding(size_t i) const {
    return {data_ + entries_[i].offset, entries_[i].size};
  }
  /// The entry of block `key` (in this region); false when the record does not hold it.
  bool find(const BlockKey& key, size_t* i) const;

 private:
  struct Entry {
    uint16_t local;
    uint32_t size;
    size_t offset;
  };
  const uint8_t* data_;
  BlockKey region_;
  std::vector<Entry> entries_;
};

/// The local index of block `b` in its region.
inline uint16_t localIndexOf(const BlockKey& b) {
  return static_cast<uint16_t>((b.x & kRegionMask) | ((b.y & kRegionMask) << kRegionBits) |
                               ((b.z & kRegionMask) << (2 * kRegionBits)));
}

/// Encodes one region's blocks (all of region `region`) into `out`. A block given as nullptr
/// keeps its encoding from `previous` (the region's earlier record; IoError naming `where`
/// when it is null or does not hold the block). Returns the blocks compressed.
size_t encodeRegion(BlockCodec& codec, const BlockKey& region, RegionBlocks blocks,
                    const BlockRecord* previous, const std::string& where, BlockRecord* out);
/// The records of `regions`, encoded on every core (a codec per thread); previous[j] (when
/// `previous` is not empty) is regions[j]'s earlier record, as for encodeRegion.
std::vector<BlockRecord> encodeRegions(const std::vector<RegionBlocks>& regions,
                                       const std::vector<const BlockRecord*>& previous = {},
                                       const std::string& where = "paging");

}  // namespace fragg
