// The SQLite page store: WAL mode (readers in other processes see the last commit while the
// map writes), synchronous=NORMAL (a commit survives the process being killed; a power loss
// may take the last commits back, never the database's integrity). Tables:
//   blocks(k BLOB PRIMARY KEY, v BLOB) WITHOUT ROWID   -- 12-byte region key -> region record
//   meta(name TEXT PRIMARY KEY, v BLOB)                -- 'map' -> the map's metadata
// PRAGMA user_version is the store format (0 in format 1's stores, keyed by block).
#include <sqlite3.h>

#include <filesystem>
#include <mutex>

#include "block_codec.h"
#include "fragg_map/errors.h"
#include "fragg_map/store/page_stores.h"
#include "region_record_store.h"

namespace fragg {

namespace {
/// PRAGMA application_id of a fragg_map store ("FGPS").
constexpr int kApplicationId = 0x46475053;

class Statement {
 public:
  Statement(sqlite3* db, const char* sql, const std::string& path) : path_(path) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK)
      throw IoError(path + ": " + sqlite3_errmsg(db));
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  sqlite3_stmt* get() { return stmt_; }
  /// SQLITE_ROW or SQLITE_DONE; IoError otherwise.
  int step() {
    const int rc = sqlite3_step(stmt_);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE)
      throw IoError(path_ + ": " + sqlite3_errmsg(sqlite3_db_handle(stmt_)));
    return rc;
  }
  void reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }

 private:
  sqlite3_stmt* stmt_ = nullptr;
  std::string path_;
};

class SqlitePageStore final : public RegionRecordStore {
 public:
  /// format1: open a store of format 1 (read-only, for readFormat1) instead of refusing it.
  SqlitePageStore(const std::string& path, bool read_only, bool format1 = false) : path_(path) {
    std::error_code ec;
    if (read_only && !std::filesystem::exists(path, ec))
      throw IoError("cannot read " + path + ": no such file");
    const int flags = read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE;
    if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
      const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      throw IoError("cannot open " + path + ": " + why);
    }
    try {
      sqlite3_busy_timeout(db_, 10000);
      const int app = pragmaInt("PRAGMA application_id");
      if (app != 0 && app != kApplicationId)
        throw IoError(path + ": an SQLite database that is not a fragg_map page store");
      if (!read_only) {
        exec("PRAGMA journal_mode=WAL");
        exec("PRAGMA synchronous=NORMAL");
        if (app == 0) {
          exec("BEGIN IMMEDIATE");
          exec(
              "CREATE TABLE IF NOT EXISTS blocks(k BLOB PRIMARY KEY, v BLOB NOT NULL) "
              "WITHOUT ROWID");
          exec("CREATE TABLE IF NOT EXISTS meta(name TEXT PRIMARY KEY, v BLOB NOT NULL)");
          exec(("PRAGMA application_id=" + std::to_string(kApplicationId)).c_str());
          exec(("PRAGMA user_version=" + std::to_string(kPageStoreFormat)).c_str());
          exec("COMMIT");
        }
      } else if (app == 0) {
        throw IoError(path + ": not a fragg_map page store (empty or another database)");
      }
      const int format =
          app == 0 ? static_cast<int>(kPageStoreFormat) : pragmaInt("PRAGMA user_version");
      if (format == 0 && !format1) refuseFormat1(path);
      if (format != (format1 ? 0 : static_cast<int>(kPageStoreFormat)))
        throw IoError(path + ": a page store of format " + std::to_string(format) +
                      ", this fragg_map reads format " + std::to_string(kPageStoreFormat));
    } catch (...) {
      sqlite3_close(db_);
      throw;
    }
  }
  ~SqlitePageStore() override {
    get_.reset();
    sqlite3_close(db_);
  }

  const char* kind() const override { return "sqlite"; }
  const std::string& path() const override { return path_; }

  // Reads and commits share the connection and its lock: a read waits for a commit that the
  // map's background writer is running (LMDB's reads do not).
  void withRecords(const std::vector<BlockKey>& regions,
                   const std::function<void(const Records&)>& fn) override {
    std::vector<BlockRecord> bytes(regions.size());
    std::vector<bool> found(regions.size(), false);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!get_) get_ = std::make_unique<Statement>(db_, "SELECT v FROM blocks WHERE k=?", path_);
      exec("BEGIN");  // one snapshot
      try {
        for (size_t j = 0; j < regions.size(); ++j) {
          const StoreKey k = storeKeyOf(regions[j]);
          get_->reset();
          sqlite3_bind_blob(get_->get(), 1, k.bytes, sizeof(k.bytes), SQLITE_STATIC);
          if (get_->step() != SQLITE_ROW) continue;
          const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(get_->get(), 0));
          bytes[j].assign(p, p + sqlite3_column_bytes(get_->get(), 0));
          found[j] = true;
        }
        get_->reset();
        exec("COMMIT");
      } catch (...) {
        get_->reset();
        sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
        throw;
      }
    }
    Records records(regions.size(), {nullptr, 0});
    for (size_t j = 0; j < regions.size(); ++j)
      if (found[j]) records[j] = {bytes[j].data(), bytes[j].size()};
    fn(records);
  }

  std::vector<uint8_t> readMeta() override {
    std::lock_guard<std::mutex> lock(mutex_);
    return readMetaLocked();
  }

  std::vector<uint8_t> forEachRecord(
      const std::function<void(const BlockKey&, const void*, size_t)>& fn) override {
    std::lock_guard<std::mutex> lock(mutex_);
    exec("BEGIN");  // one snapshot for the records and the metadata
    try {
      Statement all(db_, "SELECT k, v FROM blocks", path_);
      while (all.step() == SQLITE_ROW) {
        const BlockKey key = blockKeyOfStoreKey(sqlite3_column_blob(all.get(), 0),
                                                sqlite3_column_bytes(all.get(), 0), path_);
        fn(key, sqlite3_column_blob(all.get(), 1),
           static_cast<size_t>(sqlite3_column_bytes(all.get(), 1)));
      }
      std::vector<uint8_t> meta = readMetaLocked();
      exec("COMMIT");
      return meta;
    } catch (...) {
      sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
      throw;
    }
  }

  void commitRecords(const std::vector<std::pair<BlockKey, BlockRecord>>& puts,
                     const std::vector<BlockKey>& erases,
                     const std::vector<uint8_t>& meta) override {
    std::lock_guard<std::mutex> lock(mutex_);
    exec("BEGIN IMMEDIATE");
    try {
      {
        Statement del(db_, "DELETE FROM blocks WHERE k=?", path_);
        for (const BlockKey& key : erases) {
          const StoreKey k = storeKeyOf(key);
          sqlite3_bind_blob(del.get(), 1, k.bytes, sizeof(k.bytes), SQLITE_STATIC);
          del.step();
          del.reset();
        }
        Statement put(db_, "INSERT OR REPLACE INTO blocks(k, v) VALUES(?, ?)", path_);
        for (const auto& [key, v] : puts) {
          const StoreKey k = storeKeyOf(key);
          sqlite3_bind_blob(put.get(), 1, k.bytes, sizeof(k.bytes), SQLITE_STATIC);
          sqlite3_bind_blob(put.get(), 2, v.data(), static_cast<int>(v.size()), SQLITE_STATIC);
          put.step();
          put.reset();
        }
        Statement m(db_, "INSERT OR REPLACE INTO meta(name, v) VALUES('map', ?)", path_);
        sqlite3_bind_blob(m.get(), 1, meta.data(), static_cast<int>(meta.size()), SQLITE_STATIC);
        m.step();
      }
      exec("COMMIT");
    } catch (...) {
      sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
      throw;
    }
  }

  uint64_t diskBytes() const override {
    std::error_code ec;
    uint64_t n = 0;
    for (const std::string& p : {path_, path_ + "-wal"}) {
      const auto s = std::filesystem::file_size(p, ec);
      if (!ec) n += s;
    }
    return n;
  }

 private:
  void exec(const char* sql) {
    char* err = nullptr;
    if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
      const std::string why = err ? err : sqlite3_errmsg(db_);
      sqlite3_free(err);
      throw IoError(path_ + ": " + why);
    }
  }
  int pragmaInt(const char* sql) {
    Statement s(db_, sql, path_);
    return s.step() == SQLITE_ROW ? sqlite3_column_int(s.get(), 0) : 0;
  }
  std::vector<uint8_t> readMetaLocked() {
    Statement s(db_, "SELECT v FROM meta WHERE name='map'", path_);
    if (s.step() != SQLITE_ROW) return {};
    const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(s.get(), 0));
    return std::vector<uint8_t>(p, p + sqlite3_column_bytes(s.get(), 0));
  }

  std::string path_;
  sqlite3* db_ = nullptr;
  std::mutex mutex_;
  std::unique_ptr<Statement> get_;
};
}  // namespace

std::shared_ptr<PageStore> openSqlitePageStore(const std::string& path, bool read_only) {
  return std::make_shared<SqlitePageStore>(path, read_only);
}

std::vector<uint8_t> readSqliteFormat1(
    const std::string& path, const std::function<void(const BlockKey&, const Block&)>& fn) {
  SqlitePageStore store(path, /*read_only=*/true, /*format1=*/true);
  return store.readFormat1(fn);
}

}  // namespace fragg
