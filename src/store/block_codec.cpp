#include "block_codec.h"

#include <algorithm>
#include <cstring>
#include <iterator>
#include <memory>

#include "fragg_map/errors.h"

namespace fragg {

namespace {
// zstd's first fast level: on W1's blocks it compresses twice as fast as level 1 for records
// 14 % larger (docs/benchmarks.md); lower levels are no faster. Records stay plain zstd frames:
// stores written at any level read the same.
constexpr int kLevel = -1;

/// A uniform block's record: tag, the cell, its complement.
constexpr uint8_t kUniformTag = 'U';
constexpr size_t kUniformBytes = 1 + 2 * sizeof(Cell);
static_assert(sizeof(Cell) == sizeof(uint32_t), "a cell is one 32-bit word");

/// Whether every cell equals the first; `cell` gets its bits.
bool uniform(const Block& block, uint32_t* cell) {
  uint32_t words[kCellsPerBlock];
  std::memcpy(words, block.cells, sizeof(words));
  uint32_t differ = 0;
  for (int c = 1; c < kCellsPerBlock; ++c) differ |= words[c] ^ words[0];
  *cell = words[0];
  return differ == 0;
}
}  // namespace

BlockCodec::BlockCodec() : cctx_(ZSTD_createCCtx()), dctx_(ZSTD_createDCtx()) {
  if (!cctx_ || !dctx_) throw IoError("zstd: cannot create a compression context");
  ZSTD_CCtx_setParameter(cctx_, ZSTD_c_compressionLevel, kLevel);
  ZSTD_CCtx_setParameter(cctx_, ZSTD_c_checksumFlag, 1);
  buffer_.resize(ZSTD_compressBound(sizeof(Block)));
}

BlockCodec::~BlockCodec() {
  ZSTD_freeCCtx(cctx_);
  ZSTD_freeDCtx(dctx_);
}

const std::vector<uint8_t>& BlockCodec::encode(const Block& block) {
  uint32_t cell = 0;
  if (uniform(block, &cell)) {
    const uint32_t check = ~cell;
    buffer_.resize(kUniformBytes);
    buffer_[0] = kUniformTag;
    std::memcpy(&buffer_[1], &cell, sizeof(cell));
    std::memcpy(&buffer_[1 + sizeof(cell)], &check, sizeof(check));
    return buffer_;
  }
  buffer_.resize(ZSTD_compressBound(sizeof(Block)));
  const size_t n = ZSTD_compress2(cctx_, buffer_.data(), buffer_.size(), &block, sizeof(Block));
  if (ZSTD_isError(n)) throw IoError(std::string("zstd: ") + ZSTD_getErrorName(n));
  buffer_.resize(n);
  return buffer_;
}

void BlockCodec::decode(const void* data, size_t size, Block* out, const std::string& where) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  if (size == kUniformBytes && bytes[0] == kUniformTag) {
    uint32_t cell = 0, check = 0;
    std::memcpy(&cell, bytes + 1, sizeof(cell));
    std::memcpy(&check, bytes + 1 + sizeof(cell), sizeof(check));
    if (check != ~cell) throw IoError(where + ": uniform block record fails its check");
    uint32_t words[kCellsPerBlock];
    std::fill(std::begin(words), std::end(words), cell);
    std::memcpy(out->cells, words, sizeof(words));
    return;
  }
  const unsigned long long content = ZSTD_getFrameContentSize(data, size);
  if (content != sizeof(Block))
    throw IoError(where + ": block record does not hold a " + std::to_string(sizeof(Block)) +
                  "-byte block");
  const size_t n = ZSTD_decompressDCtx(dctx_, out, sizeof(Block), data, size);
  if (ZSTD_isError(n) || n != sizeof(Block))
    throw IoError(where + ": block record does not decompress (" +
                  (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "wrong size") + ")");
}

std::vector<std::vector<uint8_t>> encodeBlocks(const std::vector<const Block*>& blocks) {
  std::vector<std::vector<uint8_t>> out(blocks.size());
  const long n = static_cast<long>(blocks.size());
  bool failed = false;
  std::string why;
#pragma omp parallel if (n > 256)
  {
    // A context per thread, made once per call (cheap against the blocks it compresses).
    std::unique_ptr<BlockCodec> codec;
    try {
      codec = std::make_unique<BlockCodec>();
    } catch (const std::exception& e) {
#pragma omp critical(fragg_encode_blocks)
      {
        failed = true;
        why = e.what();
      }
    }
#pragma omp for schedule(static)
    for (long j = 0; j < n; ++j) {
      if (!codec) continue;
      try {
        out[j] = codec->encode(*blocks[j]);
      } catch (const std::exception& e) {
#pragma omp critical(fragg_encode_blocks)
        {
          failed = true;
          why = e.what();
        }
      }
    }
  }
  if (failed) throw IoError(why);
  return out;
}

void decodeBlock(const void* data, size_t size, Block* out, const std::string& where) {
  thread_local std::unique_ptr<BlockCodec> codec;
  if (!codec) codec = std::make_unique<BlockCodec>();
  codec->decode(data, size, out, where);
}

void decodeBlocks(const std::vector<std::pair<const void*, size_t>>& records,
                  const std::vector<Block*>& outs, const std::string& where) {
  const long n = static_cast<long>(records.size());
  bool failed = false;
  std::string why;
#pragma omp parallel for schedule(static) if (n > 64)
  for (long j = 0; j < n; ++j) {
    try {
      decodeBlock(records[j].first, records[j].second, outs[j], where);
    } catch (const std::exception& e) {
#pragma omp critical(fragg_decode_blocks)
      {
        failed = true;
        why = e.what();
      }
    }
  }
  if (failed) throw IoError(why);
}

StoreKey storeKeyOf(const BlockKey& key) {
  StoreKey k;
  const int32_t v[3] = {key.z, key.y, key.x};
  for (int a = 0; a < 3; ++a) {
    const uint32_t u = static_cast<uint32_t>(v[a]) ^ 0x80000000u;
    for (int b = 0; b < 4; ++b) k.bytes[4 * a + b] = static_cast<uint8_t>(u >> (24 - 8 * b));
  }
  return k;
}

BlockKey blockKeyOfStoreKey(const void* data, size_t size, const std::string& where) {
  if (size != sizeof(StoreKey::bytes)) throw IoError(where + ": block record key is not 12 bytes");
  const auto* p = static_cast<const uint8_t*>(data);
  int32_t v[3];
  for (int a = 0; a < 3; ++a) {
    uint32_t u = 0;
    for (int b = 0; b < 4; ++b) u = (u << 8) | p[4 * a + b];
    v[a] = static_cast<int32_t>(u ^ 0x80000000u);
  }
  return {v[2], v[1], v[0]};
}

}  // namespace fragg
