// The LMDB page store (built when LMDB is found): one file (MDB_NOSUBDIR) plus its lock file
// "<path>-lock", named databases "blocks" (12-byte region key -> region record) and "meta"
// ("map": the map's metadata; "format": the store format, a uint32, absent in format 1). Commits
// sync the data, not the meta page (MDB_NOMETASYNC): a commit survives the process being
// killed; a power loss may take the last commit back, never the database's integrity.
#include "fragg_map/errors.h"
#include "fragg_map/store/page_stores.h"

#if FRAGG_HAVE_LMDB
#include <lmdb.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>

#include "block_codec.h"
#include "region_record_store.h"
#endif

namespace fragg {

#if FRAGG_HAVE_LMDB
namespace {
/// Address space reserved for the map file (the file grows only as records are written).
constexpr size_t kMapSizeBytes = size_t{1} << 40;
/// Resident shared pages (the store's map and the libraries) above which the store's mapped
/// pages are dropped.
constexpr size_t kDropAboveBytes = size_t{64} << 20;

class LmdbPageStore final : public RegionRecordStore {
 public:
  /// format1: open a store of format 1 (read-only, for readFormat1) instead of refusing it.
  LmdbPageStore(const std::string& path, bool read_only, bool format1 = false) : path_(path) {
    std::error_code ec;
    if (read_only && !std::filesystem::exists(path, ec))
      throw IoError("cannot read " + path + ": no such file");
    check(mdb_env_create(&env_), "create");
    try {
      check(mdb_env_set_mapsize(env_, kMapSizeBytes), "set map size");
      check(mdb_env_set_maxdbs(env_, 2), "set databases");
      const unsigned flags = MDB_NOSUBDIR | MDB_NOTLS | (read_only ? MDB_RDONLY : MDB_NOMETASYNC);
      check(mdb_env_open(env_, path.c_str(), flags, 0644), "open");
      MDB_txn* txn = nullptr;
      check(mdb_txn_begin(env_, nullptr, read_only ? MDB_RDONLY : 0, &txn), "begin");
      const unsigned create = read_only ? 0 : MDB_CREATE;
      int rc = mdb_dbi_open(txn, "blocks", create, &blocks_);
      if (rc == 0) rc = mdb_dbi_open(txn, "meta", create, &meta_);
      if (rc != 0) {
        mdb_txn_abort(txn);
        if (rc == MDB_NOTFOUND) throw IoError(path + ": not a fragg_map page store");
        check(rc, "open databases");
      }
      try {
        checkFormat(txn, read_only, format1);
      } catch (...) {
        mdb_txn_abort(txn);
        throw;
      }
      check(mdb_txn_commit(txn), "commit");
    } catch (...) {
      mdb_env_close(env_);
      throw;
    }
    locateMap();
  }
  ~LmdbPageStore() override { mdb_env_close(env_); }

  const char* kind() const override { return "lmdb"; }
  const std::string& path() const override { return path_; }

  // Reads take no lock: LMDB's read transactions run beside the write transaction of a
  // commit on another thread (the map's background writer) and see the last finished commit.
  std::vector<uint8_t> readMeta() override {
    ReadTxn txn(*this);
    return metaIn(txn.txn);
  }

  void withRecords(const std::vector<BlockKey>& regions,
                   const std::function<void(const Records&)>& fn) override {
    ReadTxn txn(*this);  // one snapshot; the values stay valid until it ends
    Records records(regions.size(), {nullptr, 0});
    for (size_t j = 0; j < regions.size(); ++j) {
      StoreKey sk = storeKeyOf(regions[j]);
      MDB_val k{sizeof(sk.bytes), sk.bytes}, v;
      const int rc = mdb_get(txn.txn, blocks_, &k, &v);
      if (rc == MDB_NOTFOUND) continue;
      check(rc, "read");
      records[j] = {v.mv_data, v.mv_size};
    }
    fn(records);
    // A page-in batch reads records all over the store: without this, the file pages it
    // touched stay in the process's resident memory until the next commit drops them (the
    // paged W4 build peaked 365 MiB above the same build on SQLite).
    dropMappedPages();
  }

  std::vector<uint8_t> forEachRecord(
      const std::function<void(const BlockKey&, const void*, size_t)>& fn) override {
    ReadTxn txn(*this);  // one snapshot for the records and the metadata
    forEachRecordIn(txn.txn, [&](const MDB_val& k, const MDB_val& v) {
      fn(blockKeyOfStoreKey(k.mv_data, k.mv_size, path_), v.mv_data, v.mv_size);
    });
    return metaIn(txn.txn);
  }

  void commitRecords(const std::vector<std::pair<BlockKey, BlockRecord>>& puts,
                     const std::vector<BlockKey>& erases,
                     const std::vector<uint8_t>& meta) override {
    std::lock_guard<std::mutex> lock(mutex_);
    MDB_txn* txn = nullptr;
    check(mdb_txn_begin(env_, nullptr, 0, &txn), "begin");
    try {
      for (const BlockKey& key : erases) {
        StoreKey sk = storeKeyOf(key);
        MDB_val k{sizeof(sk.bytes), sk.bytes};
        const int rc = mdb_del(txn, blocks_, &k, nullptr);
        if (rc != MDB_NOTFOUND) check(rc, "erase");
      }
      size_t written = 0;
      for (const auto& [key, bytes] : puts) {
        StoreKey sk = storeKeyOf(key);
        MDB_val k{sizeof(sk.bytes), sk.bytes};
        MDB_val v{bytes.size(), const_cast<uint8_t*>(bytes.data())};
        check(mdb_put(txn, blocks_, &k, &v, 0), "write");
        if (++written % 8192 == 0) dropMappedPages();
      }
      char name[] = "map";
      MDB_val k{3, name};
      MDB_val v{meta.size(), const_cast<uint8_t*>(meta.data())};
      check(mdb_put(txn, meta_, &k, &v, 0), "write metadata");
    } catch (...) {
      mdb_txn_abort(txn);
      throw;
    }
    check(mdb_txn_commit(txn), "commit");
    dropMappedPages();
  }

  void releaseMappedPages() override { dropMappedPages(); }

  /// A write transaction holds a copy of every page it writes in its own memory until it
  /// commits (the map is read-only): the records' bytes, and the tree pages above them.
  size_t commitMemoryBytes(size_t record_bytes) const override {
    return record_bytes + record_bytes / 8;
  }

  uint64_t diskBytes() const override {
    std::error_code ec;
    const auto s = std::filesystem::file_size(path_, ec);
    return ec ? 0 : s;
  }

 private:
  struct ReadTxn {
    explicit ReadTxn(LmdbPageStore& s) {
      s.check(mdb_txn_begin(s.env_, nullptr, MDB_RDONLY, &txn), "begin read");
    }
    ~ReadTxn() { mdb_txn_abort(txn); }
    MDB_txn* txn = nullptr;
  };

  /// Drops the map's file pages from this process's resident memory: every record read or
  /// written (a put reads its leaf through the map) maps file pages into the process, and a
  /// commit's puts reach most leaves of the store (keys in z, y, x order), so without this
  /// the process's resident memory grows with the store. Safe inside a transaction: the map
  /// is read-only and shared (pages come back from the page cache when touched), a write
  /// transaction's dirty pages are in its own memory until the commit.
  void dropMappedPages() {
    // Dropping costs the pages touched again (faults) and a TLB shootdown on every core the
    // process runs on: only once the mapped pages pass a bound (W4: a drop at every page-in
    // and every 8192 puts put the kernel's share of the paged build at 8 %).
    if (sharedResidentBytes() < kDropAboveBytes) return;
    MDB_envinfo info;
    MDB_stat stat;
    if (!map_addr_ || mdb_env_info(env_, &info) != 0 || mdb_env_stat(env_, &stat) != 0) return;
    const size_t used = (static_cast<size_t>(info.me_last_pgno) + 1) * stat.ms_psize;
    madvise(map_addr_, std::min(used, map_bytes_), MADV_DONTNEED);
  }
  /// The process's resident shared pages (file-backed: the store's map, the libraries),
  /// from /proc/self/statm; the bound when it cannot be read (pages are then dropped).
  static size_t sharedResidentBytes() {
    std::ifstream statm("/proc/self/statm");
    size_t size = 0, resident = 0, shared = 0;
    if (!(statm >> size >> resident >> shared)) return kDropAboveBytes;
    return shared * static_cast<size_t>(sysconf(_SC_PAGESIZE));
  }
  /// Where LMDB mapped the file (mdb_env_info gives the address only with MDB_FIXEDMAP): the
  /// largest mapping of the file in /proc/self/maps. None found: pages are not dropped.
  void locateMap() {
    std::error_code ec;
    const std::string file = std::filesystem::canonical(path_, ec).string();
    if (ec) return;
    std::ifstream maps("/proc/self/maps");
    std::string line;
    while (std::getline(maps, line)) {
      const size_t slash = line.find('/');
      if (slash == std::string::npos || line.compare(slash, std::string::npos, file) != 0) continue;
      unsigned long start = 0, end = 0;
      if (std::sscanf(line.c_str(), "%lx-%lx", &start, &end) != 2) continue;
      if (end - start > map_bytes_) {
        map_addr_ = reinterpret_cast<void*>(start);
        map_bytes_ = end - start;
      }
    }
  }

  void check(int rc, const char* what) const {
    if (rc != 0) throw IoError(path_ + ": LMDB " + what + ": " + mdb_strerror(rc));
  }
  /// The store's format ("format" in meta): a new store gets kPageStoreFormat; a store with
  /// blocks or a map but no format is of format 1, refused unless `format1`.
  void checkFormat(MDB_txn* txn, bool read_only, bool format1) {
    char name[] = "format";
    MDB_val k{6, name}, v;
    int rc = mdb_get(txn, meta_, &k, &v);
    if (rc == 0) {
      uint32_t format = 0;
      if (v.mv_size == sizeof(format)) std::memcpy(&format, v.mv_data, sizeof(format));
      if (format != kPageStoreFormat || format1)
        throw IoError(path_ + ": a page store of format " + std::to_string(format) +
                      ", this fragg_map reads format " + std::to_string(kPageStoreFormat));
      return;
    }
    if (rc != MDB_NOTFOUND) check(rc, "read the format");
    MDB_stat blocks, meta;
    check(mdb_stat(txn, blocks_, &blocks), "stat");
    check(mdb_stat(txn, meta_, &meta), "stat");
    if (blocks.ms_entries > 0 || meta.ms_entries > 0) {
      if (!format1) refuseFormat1(path_);
      return;
    }
    if (format1) throw IoError(path_ + ": an empty page store (no store of format 1)");
    if (read_only) return;  // empty: nothing to read, whatever its format
    uint32_t format = kPageStoreFormat;
    MDB_val fv{sizeof(format), &format};
    check(mdb_put(txn, meta_, &k, &fv, 0), "write the format");
  }

  template <class Fn>
  void forEachRecordIn(MDB_txn* txn, Fn&& fn) {
    MDB_cursor* cursor = nullptr;
    check(mdb_cursor_open(txn, blocks_, &cursor), "cursor");
    MDB_val k, v;
    int rc = mdb_cursor_get(cursor, &k, &v, MDB_FIRST);
    try {
      while (rc == 0) {
        fn(k, v);
        rc = mdb_cursor_get(cursor, &k, &v, MDB_NEXT);
      }
    } catch (...) {
      mdb_cursor_close(cursor);
      throw;
    }
    mdb_cursor_close(cursor);
    if (rc != MDB_NOTFOUND) check(rc, "iterate");
  }
  std::vector<uint8_t> metaIn(MDB_txn* txn) {
    char name[] = "map";
    MDB_val k{3, name}, v;
    const int rc = mdb_get(txn, meta_, &k, &v);
    if (rc == MDB_NOTFOUND) return {};
    check(rc, "read metadata");
    const auto* p = static_cast<const uint8_t*>(v.mv_data);
    return std::vector<uint8_t>(p, p + v.mv_size);
  }

  std::string path_;
  MDB_env* env_ = nullptr;
  MDB_dbi blocks_ = 0, meta_ = 0;
  void* map_addr_ = nullptr;  ///< LMDB's map of the file (locateMap)
  size_t map_bytes_ = 0;
  std::mutex mutex_;  ///< one commit at a time
};
}  // namespace

bool lmdbAvailable() { return true; }

std::shared_ptr<PageStore> openLmdbPageStore(const std::string& path, bool read_only) {
  return std::make_shared<LmdbPageStore>(path, read_only);
}

std::vector<uint8_t> readLmdbFormat1(const std::string& path,
                                     const std::function<void(const BlockKey&, const Block&)>& fn) {
  LmdbPageStore store(path, /*read_only=*/true, /*format1=*/true);
  return store.readFormat1(fn);
}
#else
bool lmdbAvailable() { return false; }

std::shared_ptr<PageStore> openLmdbPageStore(const std::string& path, bool) {
  throw InvalidArgument(path + ": this fragg_map was built without LMDB");
}

std::vector<uint8_t> readLmdbFormat1(const std::string& path,
                                     const std::function<void(const BlockKey&, const Block&)>&) {
  throw InvalidArgument(path + ": this fragg_map was built without LMDB");
}
#endif

}  // namespace fragg
