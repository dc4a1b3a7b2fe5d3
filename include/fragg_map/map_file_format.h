// The .fgm map file (DESIGN §7), little-endian:
//   header : "FRAGGMAP" | u32 version | u32 header bytes | f64 resolution_m |
//            f64 prob_hit, prob_miss, clamp_min, clamp_max, unknown_band |
//            u32 block edge (8) | u32 flags (bit 0: blocks zlib-compressed, bit 1: kept
//            scans, bit 2: sub-map region) |
//            u64 block count | u64 scans integrated
//   blocks : i32 x, y, z | u32 payload bytes | payload (512 x {i16 hits, i16 log_odds_fx}),
//            sorted by key so the same map always gives the same bytes
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
/// Versions 1 (no scan section), 2 (kept scans without range noise) and 3 (no region section)
/// are read too. A map without a region is written as in version 3, with version 4.
constexpr uint32_t kMapFileVersion = 4;
constexpr uint32_t kMapFileCompressed = 1u;
constexpr uint32_t kMapFileScans = 2u;
constexpr uint32_t kMapFileRegion = 4u;

}  // namespace fragg
