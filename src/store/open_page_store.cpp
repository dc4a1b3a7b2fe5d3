#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <tuple>
#include <utility>

#include "fragg_map/errors.h"
#include "fragg_map/store/page_stores.h"

namespace fragg {

namespace {
std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

/// An existing non-empty file: SQLite by its header, else LMDB; otherwise false.
bool kindOfExistingFile(const std::string& path, PageStoreKind* kind) {
  std::ifstream in(path, std::ios::binary);
  char head[16] = {};
  if (!in.read(head, sizeof(head))) return false;
  *kind =
      std::memcmp(head, "SQLite format 3", 16) == 0 ? PageStoreKind::kSqlite : PageStoreKind::kLmdb;
  return true;
}
}  // namespace

PageStoreKind defaultPageStoreKind() {
  return lmdbAvailable() ? PageStoreKind::kLmdb : PageStoreKind::kSqlite;
}

PageStoreKind pageStoreKindOf(const std::string& path) {
  PageStoreKind kind;
  if (kindOfExistingFile(path, &kind)) return kind;
  const std::string ext = extensionOf(path);
  if (ext == ".db" || ext == ".sqlite") return PageStoreKind::kSqlite;
  if (ext == ".lmdb" || ext == ".mdb") return PageStoreKind::kLmdb;
  return defaultPageStoreKind();
}

bool isPageStorePath(const std::string& path) {
  const std::string ext = extensionOf(path);
  return ext == ".db" || ext == ".sqlite" || ext == ".lmdb" || ext == ".mdb";
}

std::shared_ptr<PageStore> openPageStore(const std::string& path, bool read_only) {
  return pageStoreKindOf(path) == PageStoreKind::kLmdb ? openLmdbPageStore(path, read_only)
                                                       : openSqlitePageStore(path, read_only);
}

namespace {
bool storeOrder(const BlockKey& a, const BlockKey& b) {
  return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
}
}  // namespace

ConvertStats convertPageStore(const std::string& from, const std::string& to, size_t batch_blocks) {
  std::error_code ec;
  if (std::filesystem::exists(to, ec))
    throw IoError("cannot convert into " + to + ": it exists (give a new store)");
  // Written under another name, renamed when complete: a conversion cut short leaves no store
  // that looks like a map.
  const std::string partial = to + ".converting";
  for (const char* suffix : {"", "-wal", "-shm", "-lock", "-journal"})
    std::filesystem::remove(partial + suffix, ec);
  const PageStoreKind to_kind = pageStoreKindOf(to);
  ConvertStats stats;
  {
    auto store = to_kind == PageStoreKind::kLmdb ? openLmdbPageStore(partial, false)
                                                 : openSqlitePageStore(partial, false);
    // Format 1 lists blocks in z, y, x order: a slab of regions (4 block layers in z) is
    // complete once a block of a higher slab comes, and is written then.
    std::map<BlockKey, std::vector<std::pair<BlockKey, Block>>, decltype(&storeOrder)> open(
        storeOrder);
    size_t held = 0;
    auto write = [&](int32_t below_region_z, const std::vector<uint8_t>& meta) {
      std::vector<RegionBlocks> regions;
      std::vector<BlockKey> keys;
      for (auto it = open.begin(); it != open.end() && it->first.z < below_region_z; ++it) {
        RegionBlocks rb;
        for (const auto& [k, b] : it->second) rb.emplace_back(k, &b);
        regions.push_back(std::move(rb));
        keys.push_back(it->first);
      }
      if (regions.empty() && meta.empty()) return;
      std::vector<BlockRecord> records = store->encode(regions);
      std::vector<std::pair<BlockKey, BlockRecord>> puts;
      for (size_t j = 0; j < records.size(); ++j) puts.emplace_back(keys[j], std::move(records[j]));
      // Meanwhile a metadata record of no map: a store cut short here is not a map.
      store->commitRecords(puts, {}, meta.empty() ? std::vector<uint8_t>{0} : meta);
      stats.records += puts.size();
      for (const BlockKey& k : keys) {
        held -= open[k].size();
        open.erase(k);
      }
    };
    auto read = [&](const BlockKey& key, const Block& block) {
      const BlockKey region = regionOf(key);
      if (held >= batch_blocks && !open.empty() && open.begin()->first.z < region.z)
        write(region.z, {});
      open[region].emplace_back(key, block);
      ++held;
      ++stats.blocks;
    };
    const std::vector<uint8_t> meta = pageStoreKindOf(from) == PageStoreKind::kLmdb
                                          ? readLmdbFormat1(from, read)
                                          : readSqliteFormat1(from, read);
    if (meta.empty()) throw IoError(from + ": the page store holds no map");
    write(std::numeric_limits<int32_t>::max(), meta);
  }
  std::filesystem::rename(partial, to);
  std::filesystem::remove(partial + "-lock", ec);
  return stats;
}

}  // namespace fragg
