// The block section of .fgm version 5 (map_file_format.h): blocks in chunks of up to
// kFileChunkBlocks, each chunk compressed on its own so that chunks are packed and unpacked on
// threads. Inside a chunk (before compression): n x (i32 x, y, z), then per block its 512 hit
// counts (i16) followed by its 512 log-odds (i16): like values side by side compress better.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fragg_map/cell.h"
#include "fragg_map/internal/byte_io.h"
#include "fragg_map/key.h"

namespace fragg {

/// Which compressor packed the chunks (the section's first field).
enum class ChunkCodec : uint32_t { kZlib = 1, kZstd = 2 };

constexpr uint32_t kFileChunkBlocks = 256;  // 512 KiB of cells before compression

/// zstd where this build has it (faster at a better ratio), else zlib.
ChunkCodec bestChunkCodec();
bool chunkCodecAvailable(ChunkCodec codec);
const char* chunkCodecName(ChunkCodec codec);

/// Writes u32 codec | u32 blocks per chunk | per chunk: u32 packed bytes | packed chunk. The
/// blocks are `count` in file order; `fetch(first, n, out)` fills `out` with n block
/// pointers from block `first` on (called on the calling thread only, in order: a paged-out
/// block can be read into storage that stays valid until the next call). Chunks are
/// compressed on up to `threads` threads (0 = every core).
void writeBlockChunks(
    ByteWriter& w, ChunkCodec codec, size_t count, const std::vector<BlockKey>& keys,
    const std::function<void(size_t first, size_t n, std::vector<const Block*>& out)>& fetch,
    int threads = 0);

/// Reads a section written by writeBlockChunks with `count` blocks. `create(key)` is called on
/// the calling thread in file order and returns where the block's cells go (nullptr: reject
/// as a duplicate); the cells are written there on threads, then `check(block)` (on threads)
/// returns why they are invalid, or an empty string. Errors throw IoError through `r`.
void readBlockChunks(ByteReader& r, uint64_t count,
                     const std::function<Block*(const BlockKey&)>& create,
                     const std::function<std::string(const Block&)>& check, int threads = 0);

}  // namespace fragg
