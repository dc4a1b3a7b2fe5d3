// The .fgm map file (DESIGN §7), little-endian:
//   header : "FRAGGMAP" | u32 version | u32 header bytes | f64 resolution_m |
//            f64 prob_hit, prob_miss, clamp_min, clamp_max, unknown_band |
//            u32 block edge (8) | u32 flags (bit 0: blocks zlib-compressed, bit 1: kept
//            scans, bit 2: sub-map region) |
//            u64 block count | u64 scans integrated
//   blocks : sorted by key so the same map always gives the same bytes.
//            version 5: u32 codec (1 zlib, 2 zstd) | u32 blocks per chunk N | per chunk of N
//            blocks (the last one fewer): u32 packed bytes | the chunk compressed as one piece:
//            n x (i32 x, y, z), then per block 512 x i16 hits, then 512 x i16 log_odds_fx
//            (block_chunks.h; chunks are packed and unpacked on threads).
//            versions 1 to 4: per block i32 x, y, z | u32 payload bytes | payload (zlib'd
//            512 x {i16 hits, i16 log_odds_fx})
//   region : only with flag bit 2 (a sub-map; version >= 4): u32 kind (1 box, 2 outside a
//            sphere) | box: f64 min x, y, z, max x, y, z; sphere: f64 centre x, y, z, radius_m |
//            u32 frame id length | frame id bytes
//   scans  : only with flag bit 1 (the map keeps its scans for loop closure; version >= 2):
//            u64 next scan index | u64 scan count | scans in index order (scan_codec.h:
//            index, stamp, pose as 12 f64, sensor model (version 3: with its range noise and
//            the cloud's frame id), insertion and removable flags, zlib'd points)
//   footer : u32 CRC-32 (zlib) of everything before it
// Saved to a temporary file and renamed. The loader checks every field and the checksum.
#pragma once

#include <cstdint>

namespace fragg {

constexpr char kMapFileMagic[8] = {'F', 'R', 'A', 'G', 'G', 'M', 'A', 'P'};
/// Versions 1 (no scan section), 2 (kept scans without range noise), 3 (no region section)
/// and 4 (blocks one by one, zlib) are read too. Version 5 writes the blocks in compressed
/// chunks (zstd where built with it, else zlib); the other sections are as in version 4.
constexpr uint32_t kMapFileVersion = 5;
constexpr uint32_t kMapFileCompressed = 1u;
constexpr uint32_t kMapFileScans = 2u;
constexpr uint32_t kMapFileRegion = 4u;

}  // namespace fragg
