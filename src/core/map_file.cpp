// Map::save and Map::load: the .fgm format described in map_file_format.h.
#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/internal/backend.h"
#include "fragg_map/internal/block_chunks.h"
#include "fragg_map/internal/byte_io.h"
#include "fragg_map/internal/pager.h"
#include "fragg_map/internal/scan_codec.h"
#include "fragg_map/map.h"
#include "fragg_map/map_file_format.h"
#include "fragg_map/map_image.h"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the .fgm writer assumes little-endian");

namespace fragg {

namespace {
constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 * 6 + 4 + 4 + 8 + 8;
constexpr size_t kBlockBytes = sizeof(Block);

void writeRegion(ByteWriter& w, const SubmapRegion& region) {
  w.put(static_cast<uint32_t>(region.kind));
  if (region.kind == SubmapRegion::Kind::kBox) {
    for (int a = 0; a < 3; ++a) w.put(region.min_map[a]);
    for (int a = 0; a < 3; ++a) w.put(region.max_map[a]);
  } else {
    for (int a = 0; a < 3; ++a) w.put(region.center_map[a]);
    w.put(region.radius_m);
  }
  w.put(static_cast<uint32_t>(region.frame_id.size()));
  w.put(region.frame_id.data(), region.frame_id.size());
}

SubmapRegion readRegion(ByteReader& r) {
  SubmapRegion region;
  const auto kind = r.get<uint32_t>("region kind");
  if (kind == static_cast<uint32_t>(SubmapRegion::Kind::kBox)) {
    region.kind = SubmapRegion::Kind::kBox;
    for (int a = 0; a < 3; ++a) region.min_map[a] = r.get<double>("region box");
    for (int a = 0; a < 3; ++a) region.max_map[a] = r.get<double>("region box");
  } else if (kind == static_cast<uint32_t>(SubmapRegion::Kind::kOutsideSphere)) {
    region.kind = SubmapRegion::Kind::kOutsideSphere;
    for (int a = 0; a < 3; ++a) region.center_map[a] = r.get<double>("region centre");
    region.radius_m = r.get<double>("region radius");
  } else {
    r.fail("unknown region kind " + std::to_string(kind));
  }
  const auto frame_chars = r.get<uint32_t>("region frame id length");
  if (frame_chars > kMaxRegionFrameChars) r.fail("region frame id too long");
  region.frame_id.resize(frame_chars);
  r.take(region.frame_id.data(), frame_chars, "region frame id");
  try {
    region.validate();
  } catch (const InvalidArgument& e) {
    r.fail(std::string("bad region: ") + e.what());
  }
  return region;
}

// Versions 1 to 4: per block i32 x, y, z | u32 payload bytes | zlib'd (or raw) cells.
void readPerBlockSection(ByteReader& r, uint64_t count, uint32_t flags, BlockMap& blocks,
                         const std::function<std::string(const Block&)>& check) {
  std::vector<uint8_t> packed;
  for (uint64_t b = 0; b < count; ++b) {
    BlockKey key;
    key.x = r.get<int32_t>("block key");
    key.y = r.get<int32_t>("block key");
    key.z = r.get<int32_t>("block key");
    const auto size = r.get<uint32_t>("block size");
    bool created = false;
    const BlockIndex i = blocks.findOrCreate(key, &created);
    if (!created) r.fail("duplicate block");
    Block& block = blocks.block(i);
    if (flags & kMapFileCompressed) {
      if (size > r.remaining()) r.fail("truncated block");
      packed.resize(size);
      r.take(packed.data(), size, "block");
      uLongf out_size = kBlockBytes;
      if (uncompress(reinterpret_cast<Bytef*>(&block), &out_size, packed.data(), size) != Z_OK ||
          out_size != kBlockBytes)
        r.fail("block does not decompress to " + std::to_string(kBlockBytes) + " bytes");
    } else {
      if (size != kBlockBytes) r.fail("uncompressed block of wrong size");
      r.take(&block, kBlockBytes, "block");
    }
    const std::string why = check(block);
    if (!why.empty()) r.fail(why);
  }
}
}  // namespace

namespace {

void putCrcAndWrite(ByteWriter& w, const std::string& path) {
  const uint32_t crc = static_cast<uint32_t>(crc32(0L, w.bytes.data(), w.bytes.size()));
  w.put(crc);
  AtomicFile file(path);
  file.write(w.bytes.data(), w.bytes.size());
  file.commit();
}

bool keyLess(const BlockKey& a, const BlockKey& b) {
  return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
}

}  // namespace

void Map::encodeHeader(std::vector<uint8_t>* out, uint64_t block_count) const {
  const OccupancyParams& occ = params_.occupancy;
  ByteWriter w;
  w.bytes = std::move(*out);
  w.put(kMapFileMagic, sizeof(kMapFileMagic));
  w.put(kMapFileVersion);
  w.put(static_cast<uint32_t>(kHeaderBytes));
  w.put(params_.resolution_m);
  for (double v : {occ.prob_hit, occ.prob_miss, occ.clamp_min, occ.clamp_max, occ.unknown_band})
    w.put(v);
  w.put(static_cast<uint32_t>(kBlockSize));
  const bool with_scans = params_.scans.keep || scan_store_->size() > 0;
  const bool with_region = !region_.empty();
  w.put(kMapFileCompressed | (with_scans ? kMapFileScans : 0u) |
        (with_region ? kMapFileRegion : 0u));
  w.put(block_count);
  w.put(static_cast<uint64_t>(scans_));
  *out = std::move(w.bytes);
}

void Map::encodeTail(std::vector<uint8_t>* out) const {
  ByteWriter w;
  w.bytes = std::move(*out);
  if (!region_.empty()) writeRegion(w, region_);
  if (params_.scans.keep || scan_store_->size() > 0) {
    w.put(static_cast<uint64_t>(next_scan_id_));
    w.put(static_cast<uint64_t>(scan_store_->size()));
    for (ScanId id : scan_store_->ids())
      writeScan(w, scan_store_->record(id), scan_store_->points(id));
  }
  *out = std::move(w.bytes);
}

void Map::save(const std::string& path) const {
  hostBlocks();  // the backend's cache written back
  // Resident blocks, and with paging the blocks that are in the store only (kNoBlock).
  struct Entry {
    BlockKey key;
    BlockIndex index;
  };
  std::vector<Entry> order;
  order.reserve(blocks_.size());
  blocks_.forEach([&](BlockIndex i) { order.push_back({blocks_.meta(i).key, i}); });
  if (pager_)
    for (const BlockKey& k : pager_->pagedOutKeys()) order.push_back({k, kNoBlock});
  std::sort(order.begin(), order.end(),
            [](const Entry& a, const Entry& b) { return keyLess(a.key, b.key); });

  ByteWriter w;
  encodeHeader(&w.bytes, order.size());
  std::vector<BlockKey> keys(order.size());
  for (size_t i = 0; i < order.size(); ++i) keys[i] = order[i].key;
  // Paged-out blocks are read from the store a round of chunks at a time.
  std::vector<Block> paged;
  writeBlockChunks(
      w, bestChunkCodec(), order.size(), keys,
      [&](size_t first, size_t n, std::vector<const Block*>& out) {
        size_t from_store = 0;
        for (size_t i = first; i < first + n; ++i) from_store += order[i].index == kNoBlock;
        paged.resize(from_store);
        size_t next = 0;
        for (size_t i = first; i < first + n; ++i) {
          const Entry& e = order[i];
          if (e.index != kNoBlock) {
            out.push_back(&blocks_.block(e.index));
            continue;
          }
          Block& b = paged[next++];
          if (!pager_->readPagedOut(e.key, &b))  // a pending commit's copy first
            throw IoError("cannot write " + path + ": a paged-out block is missing from " +
                          pager_->store().path());
          out.push_back(&b);
        }
      },
      params_.threads);
  encodeTail(&w.bytes);
  putCrcAndWrite(w, path);
}

MapImage Map::image() const {
  if (pager_)
    throw InvalidArgument("a paged map has no image: its page store (" + pager_->store().path() +
                          ") is the map");
  hostBlocks();  // the backend's cache written back
  std::vector<std::pair<BlockKey, BlockIndex>> order;
  order.reserve(blocks_.size());
  blocks_.forEach([&](BlockIndex i) { order.emplace_back(blocks_.meta(i).key, i); });
  std::sort(order.begin(), order.end(),
            [](const auto& a, const auto& b) { return keyLess(a.first, b.first); });
  MapImage image;
  encodeHeader(&image.header, order.size());
  image.keys.reserve(order.size());
  image.blocks.reserve(order.size());
  for (const auto& [key, index] : order) {
    image.keys.push_back(key);
    image.blocks.push_back(blocks_.block(index));
  }
  encodeTail(&image.tail);
  return image;
}

void writeMapImage(const MapImage& image, const std::string& path) {
  if (image.empty()) throw InvalidArgument("cannot write " + path + ": empty map image");
  ByteWriter w;
  w.bytes.reserve(image.header.size() + image.tail.size() + image.blocks.size() * 512 + 4);
  w.put(image.header.data(), image.header.size());
  writeBlockChunks(w, bestChunkCodec(), image.blocks.size(), image.keys,
                   [&](size_t first, size_t n, std::vector<const Block*>& out) {
                     for (size_t i = first; i < first + n; ++i) out.push_back(&image.blocks[i]);
                   });
  w.put(image.tail.data(), image.tail.size());
  putCrcAndWrite(w, path);
}

Map Map::load(const std::string& path, Backend backend) {
  MapParams runtime;
  runtime.backend = backend;
  return loadFile(path, runtime, /*keep_as_file=*/true);
}

Map Map::load(const std::string& path, const MapParams& runtime) {
  return loadFile(path, runtime, /*keep_as_file=*/false);
}

Map Map::loadFile(const std::string& path, const MapParams& runtime, bool keep_as_file) {
  const std::vector<uint8_t> bytes = readWholeFile(path);
  if (bytes.size() < kHeaderBytes + 4)
    throw IoError(path + ": not a valid .fgm map: file too short (" + std::to_string(bytes.size()) +
                  " bytes)");
  ByteReader r(bytes, bytes.size() - 4, path, "not a valid .fgm map");
  char magic[8];
  r.take(magic, sizeof(magic), "magic");
  if (std::memcmp(magic, kMapFileMagic, sizeof(magic)) != 0) r.fail("wrong magic (not FRAGGMAP)");
  const auto version = r.get<uint32_t>("version");
  if (version < 1 || version > kMapFileVersion)
    r.fail("unsupported version " + std::to_string(version) + " (this build reads versions 1 to " +
           std::to_string(kMapFileVersion) + ")");
  uint32_t stored_crc;
  std::memcpy(&stored_crc, bytes.data() + bytes.size() - 4, 4);
  if (static_cast<uint32_t>(crc32(0L, bytes.data(), bytes.size() - 4)) != stored_crc)
    r.fail("checksum mismatch (file corrupted or truncated)");
  if (r.get<uint32_t>("header size") != kHeaderBytes) r.fail("unexpected header size");

  MapParams params = runtime;  // the file's fields below replace the runtime ones
  params.resolution_m = r.get<double>("resolution");
  OccupancyParams& occ = params.occupancy;
  occ.prob_hit = r.get<double>("prob_hit");
  occ.prob_miss = r.get<double>("prob_miss");
  occ.clamp_min = r.get<double>("clamp_min");
  occ.clamp_max = r.get<double>("clamp_max");
  occ.unknown_band = r.get<double>("unknown_band");
  try {
    params.validate();
  } catch (const InvalidArgument& e) {
    r.fail(std::string("bad parameters: ") + e.what());
  }
  if (r.get<uint32_t>("block edge") != static_cast<uint32_t>(kBlockSize))
    r.fail("block edge is not " + std::to_string(kBlockSize));
  const auto flags = r.get<uint32_t>("flags");
  const uint32_t known_flags = kMapFileCompressed | (version >= 2 ? kMapFileScans : 0u) |
                               (version >= 4 ? kMapFileRegion : 0u);
  if (flags & ~known_flags) r.fail("unknown flags " + std::to_string(flags));
  const auto count = r.get<uint64_t>("block count");
  const auto scans = r.get<uint64_t>("scan count");
  // Before version 5 every block takes at least 16 bytes: reject absurd counts before
  // allocating (version 5: readBlockChunks checks its chunk count).
  if (version < 5 && count > r.remaining() / 16) r.fail("block count larger than the file");

  const bool file_has_scans = (flags & kMapFileScans) != 0;
  if (keep_as_file) params.scans.keep = file_has_scans;
  Map map(params);
  const OccupancyModel& model = map.model();
  const auto cellsValid = [&](const Block& block) -> std::string {
    for (const Cell& c : block.cells) {
      if (c.hits < 0) return "negative hit count";
      if (c.observed() && (c.log_odds_fx < model.min_fx || c.log_odds_fx > model.max_fx))
        return "log-odds outside the clamping range";
    }
    return {};
  };
  if (version >= 5) {
    if (!(flags & kMapFileCompressed)) r.fail("version 5 blocks are always compressed");
    map.blocks_.reserve(static_cast<size_t>(std::min<uint64_t>(count, r.remaining())));
    readBlockChunks(
        r, count,
        [&](const BlockKey& key) -> Block* {
          bool created = false;
          const BlockIndex i = map.blocks_.findOrCreate(key, &created, /*initialise=*/false);
          return created ? &map.blocks_.block(i) : nullptr;
        },
        cellsValid, params.threads);
  } else {
    readPerBlockSection(r, count, flags, map.blocks_, cellsValid);
  }
  map.blocks_.recomputeAllMasks(model);
  if (flags & kMapFileRegion) map.region_ = readRegion(r);
  if (flags & kMapFileScans) {
    map.next_scan_id_ = r.get<uint64_t>("next scan index");
    const auto kept = r.get<uint64_t>("kept scan count");
    if (kept > r.remaining() / 64) r.fail("kept scan count larger than the file");
    for (uint64_t k = 0; k < kept; ++k) {
      ScanRecord record;
      EncodedPoints points;
      readScan(r, record, points, version);
      if (record.id >= map.next_scan_id_ || map.scan_store_->contains(record.id))
        r.fail("scan index " + std::to_string(record.id) + " repeated or out of range");
      if (params.scans.keep) map.scan_store_->add(record, std::move(points));
    }
  } else {
    map.next_scan_id_ = scans;
  }
  if (r.remaining() != 0) r.fail("trailing bytes after the last block");
  map.scans_ = static_cast<size_t>(scans);
  map.revision_ = 1;
  return map;
}

}  // namespace fragg
