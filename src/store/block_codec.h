// A block record's value: the block's 2048 bytes of cells, zstd-compressed (fast level -1) with
// a checksum; a block whose 512 cells are all equal (44 % of W4's records, free space at the
// lower clamp) is 9 bytes instead: 'U', the cell, and the cell's bitwise complement (a check),
// which no zstd frame begins with. Stores written before uniform records existed read the same.
#pragma once

#include <zstd.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "fragg_map/cell.h"

namespace fragg {

class BlockCodec {
 public:
  BlockCodec();
  ~BlockCodec();
  BlockCodec(const BlockCodec&) = delete;
  BlockCodec& operator=(const BlockCodec&) = delete;

  /// The compressed record (valid until the next call).
  const std::vector<uint8_t>& encode(const Block& block);
  /// IoError naming `where` unless the bytes decompress, checksum intact, to exactly a block.
  void decode(const void* data, size_t size, Block* out, const std::string& where);

 private:
  ZSTD_CCtx* cctx_;
  ZSTD_DCtx* dctx_;
  std::vector<uint8_t> buffer_;
};

/// The records of `blocks`, compressed on every core (a context per thread): out[j] is
/// blocks[j]'s. Compression is most of a commit's time; the database writes stay serial.
std::vector<std::vector<uint8_t>> encodeBlocks(const std::vector<const Block*>& blocks);
/// Decodes a record with this thread's codec (BlockCodec::decode).
void decodeBlock(const void* data, size_t size, Block* out, const std::string& where);
/// Decodes records[j] (data, size) into outs[j] on every core. IoError naming `where` when one
/// does not decode.
void decodeBlocks(const std::vector<std::pair<const void*, size_t>>& records,
                  const std::vector<Block*>& outs, const std::string& where);

/// The 12-byte record key: z, y, x big-endian with the sign bit flipped, so that the stores'
/// byte order is the key order (z, then y, then x).
struct StoreKey {
  uint8_t bytes[12];
};
StoreKey storeKeyOf(const BlockKey& key);
/// IoError naming `where` when the record key is not 12 bytes.
BlockKey blockKeyOfStoreKey(const void* data, size_t size, const std::string& where);

}  // namespace fragg
