#include "region_record_store.h"

#include <algorithm>
#include <map>
#include <memory>
#include <tuple>
#include <unordered_map>

#include "block_codec.h"
#include "fragg_map/errors.h"
#include "region_codec.h"

namespace fragg {

namespace {
struct StoreOrder {
  bool operator()(const BlockKey& a, const BlockKey& b) const {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  }
};
}  // namespace

void RegionRecordStore::refuseFormat1(const std::string& path) {
  throw IoError(path +
                ": a page store of format 1 (one record per block, written before records by "
                "region); convert it with `fragg_map convert-store " +
                path + " NEW_STORE`");
}

std::vector<BlockKey> RegionRecordStore::keys() {
  std::vector<BlockKey> out;
  forEachRecord([&](const BlockKey& region, const void* data, size_t size) {
    const RegionRecordView view(data, size, region, path());
    for (size_t i = 0; i < view.count(); ++i) out.push_back(view.key(i));
  });
  return out;
}

bool RegionRecordStore::read(const BlockKey& key, Block* out) {
  bool found = false;
  withRecords({regionOf(key)}, [&](const Records& records) {
    if (!records[0].first) return;
    const RegionRecordView view(records[0].first, records[0].second, regionOf(key), path());
    size_t i = 0;
    if (!view.find(key, &i)) return;
    const auto [data, size] = view.encoding(i);
    decodeBlock(data, size, out, path());
    found = true;
  });
  return found;
}

std::vector<bool> RegionRecordStore::readMany(
    const std::vector<BlockKey>& keys, const std::vector<Block*>& outs,
    std::vector<std::pair<BlockKey, BlockRecord>>* records_out) {
  std::vector<bool> found(keys.size(), false);
  if (keys.empty()) return found;
  std::unordered_map<BlockKey, size_t, BlockKeyHash> slot;
  std::vector<BlockKey> regions;
  std::vector<size_t> region_of_key(keys.size());
  for (size_t j = 0; j < keys.size(); ++j) {
    const auto [it, added] = slot.emplace(regionOf(keys[j]), regions.size());
    if (added) regions.push_back(it->first);
    region_of_key[j] = it->second;
  }
  withRecords(regions, [&](const Records& records) {
    std::vector<std::unique_ptr<RegionRecordView>> views(regions.size());
    for (size_t r = 0; r < regions.size(); ++r)
      if (records[r].first) {
        views[r] = std::make_unique<RegionRecordView>(records[r].first, records[r].second,
                                                      regions[r], path());
        if (records_out) {
          const auto* bytes = static_cast<const uint8_t*>(records[r].first);
          records_out->emplace_back(regions[r], BlockRecord(bytes, bytes + records[r].second));
        }
      }
    std::vector<std::pair<const void*, size_t>> encodings;
    std::vector<Block*> to;
    encodings.reserve(keys.size());
    to.reserve(keys.size());
    for (size_t j = 0; j < keys.size(); ++j) {
      const RegionRecordView* view = views[region_of_key[j]].get();
      size_t i = 0;
      if (!view || !view->find(keys[j], &i)) continue;
      encodings.push_back(view->encoding(i));
      to.push_back(outs[j]);
      found[j] = true;
    }
    decodeBlocks(encodings, to, path());
  });
  return found;
}

std::vector<uint8_t> RegionRecordStore::readAll(
    const std::function<void(const BlockKey&, const Block&)>& fn) {
  Block block;
  return forEachRecord([&](const BlockKey& region, const void* data, size_t size) {
    const RegionRecordView view(data, size, region, path());
    for (size_t i = 0; i < view.count(); ++i) {
      const auto [d, n] = view.encoding(i);
      decodeBlock(d, n, &block, path());
      fn(view.key(i), block);
    }
  });
}

std::vector<uint8_t> RegionRecordStore::readFormat1(
    const std::function<void(const BlockKey&, const Block&)>& fn) {
  Block block;
  return forEachRecord([&](const BlockKey& key, const void* data, size_t size) {
    decodeBlock(data, size, &block, path());
    fn(key, block);
  });
}

std::vector<BlockRecord> RegionRecordStore::encode(
    const std::vector<RegionBlocks>& regions,
    const std::vector<const BlockRecord*>& previous) const {
  return encodeRegions(regions, previous, path());
}

bool RegionRecordStore::decode(const BlockRecord& record, const BlockKey& key, Block* out) const {
  const RegionRecordView view(record.data(), record.size(), regionOf(key), path());
  size_t i = 0;
  if (!view.find(key, &i)) return false;
  const auto [data, size] = view.encoding(i);
  decodeBlock(data, size, out, path());
  return true;
}

void RegionRecordStore::commit(const std::vector<std::pair<BlockKey, const Block*>>& puts,
                               const std::vector<BlockKey>& erases,
                               const std::vector<uint8_t>& meta) {
  // The regions touched, each with its committed blocks, then the changes on top.
  std::map<BlockKey, std::map<BlockKey, Block, StoreOrder>, StoreOrder> regions;
  for (const auto& p : puts) regions[regionOf(p.first)];
  for (const BlockKey& k : erases) regions[regionOf(k)];
  std::vector<BlockKey> keys;
  for (const auto& r : regions) keys.push_back(r.first);
  withRecords(keys, [&](const Records& records) {
    for (size_t r = 0; r < keys.size(); ++r) {
      if (!records[r].first) continue;
      const RegionRecordView view(records[r].first, records[r].second, keys[r], path());
      auto& blocks = regions[keys[r]];
      for (size_t i = 0; i < view.count(); ++i) {
        const auto [data, size] = view.encoding(i);
        decodeBlock(data, size, &blocks[view.key(i)], path());
      }
    }
  });
  for (const BlockKey& k : erases) regions[regionOf(k)].erase(k);
  for (const auto& [k, b] : puts) regions[regionOf(k)][k] = *b;
  std::vector<RegionBlocks> written;
  std::vector<BlockKey> written_keys, erased;
  for (const auto& [region, blocks] : regions) {
    if (blocks.empty()) {
      erased.push_back(region);
      continue;
    }
    RegionBlocks rb;
    for (const auto& [k, b] : blocks) rb.emplace_back(k, &b);
    written.push_back(std::move(rb));
    written_keys.push_back(region);
  }
  std::vector<BlockRecord> records = encode(written);
  std::vector<std::pair<BlockKey, BlockRecord>> records_by_region;
  records_by_region.reserve(records.size());
  for (size_t j = 0; j < records.size(); ++j)
    records_by_region.emplace_back(written_keys[j], std::move(records[j]));
  commitRecords(records_by_region, erased, meta);
}

}  // namespace fragg
