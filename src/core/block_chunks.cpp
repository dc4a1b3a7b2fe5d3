#include "fragg_map/internal/block_chunks.h"

#include <omp.h>
#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#if FRAGG_HAVE_ZSTD
#include <zstd.h>
#endif

#include "fragg_map/internal/thread_count.h"

namespace fragg {

namespace {
constexpr size_t kKeyBytes = 3 * sizeof(int32_t);
constexpr size_t kCellBytes = sizeof(Block);
constexpr int kZlibLevel = 1;
#if FRAGG_HAVE_ZSTD
constexpr int kZstdLevel = 1;
#endif
/// Chunks handled per round on each thread: bounds the memory a round holds.
constexpr int kChunksPerThreadAndRound = 4;

size_t rawBytes(size_t blocks) { return blocks * (kKeyBytes + kCellBytes); }

void pack(const BlockKey* keys, const Block* const* blocks, size_t n, uint8_t* raw) {
  for (size_t i = 0; i < n; ++i) {
    const int32_t xyz[3] = {keys[i].x, keys[i].y, keys[i].z};
    std::memcpy(raw + i * kKeyBytes, xyz, kKeyBytes);
  }
  uint8_t* cells = raw + n * kKeyBytes;
  int16_t planes[2 * kCellsPerBlock];
  for (size_t i = 0; i < n; ++i) {
    const Cell* c = blocks[i]->cells;
    for (int k = 0; k < kCellsPerBlock; ++k) {
      planes[k] = c[k].hits;
      planes[kCellsPerBlock + k] = c[k].log_odds_fx;
    }
    std::memcpy(cells + i * kCellBytes, planes, kCellBytes);
  }
}

void unpackCells(const uint8_t* planes_bytes, Block* block) {
  int16_t planes[2 * kCellsPerBlock];
  std::memcpy(planes, planes_bytes, kCellBytes);
  for (int k = 0; k < kCellsPerBlock; ++k) {
    block->cells[k].hits = planes[k];
    block->cells[k].log_odds_fx = planes[kCellsPerBlock + k];
  }
}

/// One thread's compressor state.
class Packer {
 public:
  explicit Packer(ChunkCodec codec) : codec_(codec) {
#if FRAGG_HAVE_ZSTD
    if (codec_ == ChunkCodec::kZstd) {
      cctx_ = ZSTD_createCCtx();
      dctx_ = ZSTD_createDCtx();
    }
#endif
  }
  ~Packer() {
#if FRAGG_HAVE_ZSTD
    ZSTD_freeCCtx(cctx_);
    ZSTD_freeDCtx(dctx_);
#endif
  }
  Packer(const Packer&) = delete;
  Packer& operator=(const Packer&) = delete;

  /// Returns an error message, empty on success.
  std::string compress(const std::vector<uint8_t>& raw, std::vector<uint8_t>& out) {
    if (codec_ == ChunkCodec::kZlib) {
      uLongf size = compressBound(raw.size());
      out.resize(size);
      if (compress2(out.data(), &size, raw.data(), raw.size(), kZlibLevel) != Z_OK)
        return "zlib compression failed";
      out.resize(size);
      return {};
    }
#if FRAGG_HAVE_ZSTD
    if (!cctx_) return "zstd: cannot create a compression context";
    out.resize(ZSTD_compressBound(raw.size()));
    const size_t size =
        ZSTD_compressCCtx(cctx_, out.data(), out.size(), raw.data(), raw.size(), kZstdLevel);
    if (ZSTD_isError(size)) return std::string("zstd: ") + ZSTD_getErrorName(size);
    out.resize(size);
    return {};
#else
    return "this build has no zstd";
#endif
  }

  /// True when `packed` decompresses to exactly raw.size() bytes.
  bool decompress(const uint8_t* packed, size_t size, std::vector<uint8_t>& raw) {
    if (codec_ == ChunkCodec::kZlib) {
      uLongf out = raw.size();
      return uncompress(raw.data(), &out, packed, size) == Z_OK && out == raw.size();
    }
#if FRAGG_HAVE_ZSTD
    if (!dctx_) return false;
    const size_t out = ZSTD_decompressDCtx(dctx_, raw.data(), raw.size(), packed, size);
    return !ZSTD_isError(out) && out == raw.size();
#else
    return false;
#endif
  }

 private:
  ChunkCodec codec_;
#if FRAGG_HAVE_ZSTD
  ZSTD_CCtx* cctx_ = nullptr;
  ZSTD_DCtx* dctx_ = nullptr;
#endif
};
}  // namespace

ChunkCodec bestChunkCodec() {
  return chunkCodecAvailable(ChunkCodec::kZstd) ? ChunkCodec::kZstd : ChunkCodec::kZlib;
}

bool chunkCodecAvailable(ChunkCodec codec) {
  if (codec == ChunkCodec::kZlib) return true;
  return codec == ChunkCodec::kZstd && FRAGG_HAVE_ZSTD;
}

const char* chunkCodecName(ChunkCodec codec) {
  switch (codec) {
    case ChunkCodec::kZlib:
      return "zlib";
    case ChunkCodec::kZstd:
      return "zstd";
  }
  return "unknown";
}

void writeBlockChunks(
    ByteWriter& w, ChunkCodec codec, size_t count, const std::vector<BlockKey>& keys,
    const std::function<void(size_t first, size_t n, std::vector<const Block*>& out)>& fetch,
    int threads) {
  if (!chunkCodecAvailable(codec))
    throw IoError(std::string("cannot write blocks with ") + chunkCodecName(codec) +
                  ": not in this build");
  if (keys.size() != count) throw InvalidArgument("writeBlockChunks: one key per block");
  w.put(static_cast<uint32_t>(codec));
  w.put(kFileChunkBlocks);
  const int t = threadCount(threads);
  const size_t chunks = (count + kFileChunkBlocks - 1) / kFileChunkBlocks;
  const size_t per_round = static_cast<size_t>(t) * kChunksPerThreadAndRound;
  std::vector<std::vector<uint8_t>> packed(std::min(per_round, chunks));
  std::vector<std::string> errors(packed.size());
  std::vector<const Block*> blocks;
  for (size_t first_chunk = 0; first_chunk < chunks; first_chunk += per_round) {
    const size_t round = std::min(per_round, chunks - first_chunk);
    const size_t first_block = first_chunk * kFileChunkBlocks;
    const size_t round_blocks =
        std::min(count, (first_chunk + round) * kFileChunkBlocks) - first_block;
    blocks.clear();
    fetch(first_block, round_blocks, blocks);
    if (blocks.size() != round_blocks) throw IoError("writeBlockChunks: blocks missing");
#pragma omp parallel num_threads(std::min <int>(t, static_cast <int>(round)))
    {
      Packer packer(codec);
      std::vector<uint8_t> raw;
#pragma omp for schedule(dynamic, 1)
      for (size_t c = 0; c < round; ++c) {
        const size_t at = c * kFileChunkBlocks;  // within the round
        const size_t n = std::min<size_t>(kFileChunkBlocks, round_blocks - at);
        raw.resize(rawBytes(n));
        pack(keys.data() + first_block + at, blocks.data() + at, n, raw.data());
        errors[c] = packer.compress(raw, packed[c]);
      }
    }
    for (size_t c = 0; c < round; ++c) {
      if (!errors[c].empty()) throw IoError("cannot compress the blocks: " + errors[c]);
      w.put(static_cast<uint32_t>(packed[c].size()));
      w.put(packed[c].data(), packed[c].size());
    }
  }
}

void readBlockChunks(ByteReader& r, uint64_t count,
                     const std::function<Block*(const BlockKey&)>& create,
                     const std::function<std::string(const Block&)>& check, int threads) {
  const auto codec_id = r.get<uint32_t>("block codec");
  if (codec_id != static_cast<uint32_t>(ChunkCodec::kZlib) &&
      codec_id != static_cast<uint32_t>(ChunkCodec::kZstd))
    r.fail("unknown block codec " + std::to_string(codec_id));
  const auto codec = static_cast<ChunkCodec>(codec_id);
  if (!chunkCodecAvailable(codec))
    r.fail(std::string("blocks compressed with ") + chunkCodecName(codec) +
           ", which this build cannot read (built without it)");
  const auto per_chunk = r.get<uint32_t>("blocks per chunk");
  if (per_chunk == 0 || per_chunk > 65536)
    r.fail("blocks per chunk " + std::to_string(per_chunk) + " out of range");
  const uint64_t chunks = (count + per_chunk - 1) / per_chunk;
  // Every chunk takes at least its 4-byte size: reject absurd counts before allocating.
  if (chunks > r.remaining() / 4) r.fail("block count larger than the file");

  const int t = threadCount(threads);
  const size_t per_round = static_cast<size_t>(t) * kChunksPerThreadAndRound;
  std::vector<std::vector<uint8_t>> raw(std::min<uint64_t>(per_round, chunks));
  std::vector<const uint8_t*> packed(raw.size());
  std::vector<uint32_t> packed_size(raw.size());
  std::vector<std::string> errors(raw.size());
  std::vector<Block*> blocks;
  for (uint64_t first_chunk = 0; first_chunk < chunks; first_chunk += per_round) {
    const size_t round = static_cast<size_t>(std::min<uint64_t>(per_round, chunks - first_chunk));
    const uint64_t first_block = first_chunk * per_chunk;
    const auto blocksIn = [&](size_t c) {
      return static_cast<size_t>(
          std::min<uint64_t>(per_chunk, count - first_block - c * per_chunk));
    };
    for (size_t c = 0; c < round; ++c) {
      packed_size[c] = r.get<uint32_t>("chunk size");
      packed[c] = r.view(packed_size[c], "chunk");
      raw[c].resize(rawBytes(blocksIn(c)));
    }
#pragma omp parallel num_threads(std::min <int>(t, static_cast <int>(round)))
    {
      Packer packer(codec);
#pragma omp for schedule(dynamic, 1)
      for (size_t c = 0; c < round; ++c)
        errors[c] =
            packer.decompress(packed[c], packed_size[c], raw[c])
                ? std::string()
                : "chunk does not decompress to " + std::to_string(raw[c].size()) + " bytes";
    }
    for (size_t c = 0; c < round; ++c)
      if (!errors[c].empty()) r.fail(errors[c]);
    // The index is built here, in file order; the cells are copied on threads.
    blocks.clear();
    for (size_t c = 0; c < round; ++c) {
      const size_t n = blocksIn(c);
      for (size_t i = 0; i < n; ++i) {
        int32_t xyz[3];
        std::memcpy(xyz, raw[c].data() + i * kKeyBytes, kKeyBytes);
        Block* b = create(BlockKey{xyz[0], xyz[1], xyz[2]});
        if (!b) r.fail("duplicate block");
        blocks.push_back(b);
      }
    }
#pragma omp parallel for num_threads(std::min <int>(t, static_cast <int>(round))) \
    schedule(dynamic, 1)
    for (size_t c = 0; c < round; ++c) {
      const size_t n = blocksIn(c);
      const uint8_t* cells = raw[c].data() + n * kKeyBytes;
      for (size_t i = 0; i < n && errors[c].empty(); ++i) {
        Block* b = blocks[c * per_chunk + i];
        unpackCells(cells + i * kCellBytes, b);
        errors[c] = check(*b);
      }
    }
    for (size_t c = 0; c < round; ++c)
      if (!errors[c].empty()) r.fail(errors[c]);
  }
}

}  // namespace fragg
