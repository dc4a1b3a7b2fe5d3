// Writes a map as .fgm versions 1 to 4 did (blocks one by one, each zlib'd; map_file_format.h)
// so that the reading of old files stays tested after the writer moved on. The region
// section is written when `flags` has kMapFileRegion; never a scan section.
#pragma once

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "fragg_map/map.h"
#include "fragg_map/map_file_format.h"

namespace fragg::test {

inline void writeLegacyMapFile(const Map& map, const std::string& path, uint32_t version,
                               uint32_t flags) {
  std::vector<uint8_t> out;
  const auto put = [&](const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  const auto putValue = [&](auto v) { put(&v, sizeof(v)); };
  put(kMapFileMagic, sizeof(kMapFileMagic));
  putValue(version);
  putValue(uint32_t{8 + 4 + 4 + 8 * 6 + 4 + 4 + 8 + 8});
  putValue(map.resolution());
  const OccupancyParams& occ = map.params().occupancy;
  for (double v : {occ.prob_hit, occ.prob_miss, occ.clamp_min, occ.clamp_max, occ.unknown_band})
    putValue(v);
  putValue(uint32_t{kBlockSize});
  putValue(flags);
  std::vector<std::pair<BlockKey, const Block*>> blocks;
  map.forEachBlock([&](const BlockKey& k, const Block& b) { blocks.emplace_back(k, &b); });
  std::sort(blocks.begin(), blocks.end(), [](const auto& a, const auto& b) {
    return std::tie(a.first.z, a.first.y, a.first.x) < std::tie(b.first.z, b.first.y, b.first.x);
  });
  putValue(static_cast<uint64_t>(blocks.size()));
  putValue(static_cast<uint64_t>(map.scanCount()));
  std::vector<uint8_t> packed(compressBound(sizeof(Block)));
  for (const auto& [key, block] : blocks) {
    putValue(key.x);
    putValue(key.y);
    putValue(key.z);
    uLongf size = packed.size();
    compress2(packed.data(), &size, reinterpret_cast<const Bytef*>(block), sizeof(Block), 1);
    putValue(static_cast<uint32_t>(size));
    put(packed.data(), size);
  }
  if (flags & kMapFileRegion) {
    const SubmapRegion& r = map.region();
    putValue(static_cast<uint32_t>(r.kind));
    if (r.kind == SubmapRegion::Kind::kBox) {
      for (int a = 0; a < 3; ++a) putValue(r.min_map[a]);
      for (int a = 0; a < 3; ++a) putValue(r.max_map[a]);
    } else {
      for (int a = 0; a < 3; ++a) putValue(r.center_map[a]);
      putValue(r.radius_m);
    }
    putValue(static_cast<uint32_t>(r.frame_id.size()));
    put(r.frame_id.data(), r.frame_id.size());
  }
  putValue(static_cast<uint32_t>(crc32(0L, out.data(), out.size())));
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
}

}  // namespace fragg::test
