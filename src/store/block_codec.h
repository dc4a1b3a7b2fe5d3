// A block record's value: the block's 2048 bytes of cells, zstd-compressed with a checksum.
#pragma once

#include <zstd.h>

#include <cstdint>
#include <string>
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

/// The 12-byte record key: z, y, x big-endian with the sign bit flipped, so that the stores'
/// byte order is the key order (z, then y, then x).
struct StoreKey {
  uint8_t bytes[12];
};
StoreKey storeKeyOf(const BlockKey& key);
/// IoError naming `where` when the record key is not 12 bytes.
BlockKey blockKeyOfStoreKey(const void* data, size_t size, const std::string& where);

}  // namespace fragg
