// Store formats (issue 36): a store of format 1 (one record per block, what fragg_map wrote
// before records by region) is refused on open with one line naming `fragg_map convert-store`,
// and converting it gives a store of format 2 that holds the same map.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <zstd.h>
#if FRAGG_TEST_LMDB
#include <lmdb.h>
#endif

#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/internal/pager.h"
#include "fragg_map/store/page_stores.h"
#include "paging_scenes.h"

namespace fragg::test {
namespace {

/// A format-1 block record as main wrote it: 'U', the cell, its complement for a uniform
/// block, else the cells as a zstd frame with a checksum.
std::vector<uint8_t> format1Record(const Block& block) {
  uint32_t words[kCellsPerBlock];
  std::memcpy(words, block.cells, sizeof(words));
  bool uniform = true;
  for (uint32_t w : words) uniform &= w == words[0];
  if (uniform) {
    std::vector<uint8_t> r(9, 'U');
    const uint32_t check = ~words[0];
    std::memcpy(&r[1], &words[0], 4);
    std::memcpy(&r[5], &check, 4);
    return r;
  }
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
  std::vector<uint8_t> r(ZSTD_compressBound(sizeof(Block)));
  const size_t n = ZSTD_compress2(cctx, r.data(), r.size(), &block, sizeof(Block));
  ZSTD_freeCCtx(cctx);
  EXPECT_FALSE(ZSTD_isError(n));
  r.resize(n);
  return r;
}

/// The 12-byte record key of format 1 (and of format 2's regions): z, y, x big-endian, sign
/// bit flipped.
std::vector<uint8_t> recordKey(const BlockKey& k) {
  std::vector<uint8_t> out;
  for (int32_t v : {k.z, k.y, k.x}) {
    const uint32_t u = static_cast<uint32_t>(v) ^ 0x80000000u;
    for (int b = 0; b < 4; ++b) out.push_back(static_cast<uint8_t>(u >> (24 - 8 * b)));
  }
  return out;
}

Map sampleMap() {
  Map map(corridorParams());
  for (int i = 0; i < 4; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, 80);
    map.insert(corridorScan(T), T, corridorSensor());
  }
  return map;
}

std::vector<uint8_t> sampleMeta(const Map& map) {
  StoreMapMeta meta;
  meta.resolution_m = map.params().resolution_m;
  meta.occupancy = map.params().occupancy;
  meta.scans = map.scanCount();
  return encodeStoreMeta(meta);
}

void writeSqliteFormat1(const std::string& path, const Map& map) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  auto exec = [&](const std::string& sql) {
    ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sql;
  };
  exec("CREATE TABLE blocks(k BLOB PRIMARY KEY, v BLOB NOT NULL) WITHOUT ROWID");
  exec("CREATE TABLE meta(name TEXT PRIMARY KEY, v BLOB NOT NULL)");
  exec("PRAGMA application_id=1179078739");  // "FGPS", no user_version: format 1
  sqlite3_stmt* put = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "INSERT INTO blocks(k, v) VALUES(?, ?)", -1, &put, nullptr),
            SQLITE_OK);
  exec("BEGIN");
  map.forEachBlock([&](const BlockKey& k, const Block& b) {
    const std::vector<uint8_t> key = recordKey(k), value = format1Record(b);
    sqlite3_bind_blob(put, 1, key.data(), static_cast<int>(key.size()), SQLITE_TRANSIENT);
    sqlite3_bind_blob(put, 2, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT);
    EXPECT_EQ(sqlite3_step(put), SQLITE_DONE);
    sqlite3_reset(put);
  });
  sqlite3_finalize(put);
  const std::vector<uint8_t> meta = sampleMeta(map);
  sqlite3_stmt* m = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "INSERT INTO meta(name, v) VALUES('map', ?)", -1, &m, nullptr),
            SQLITE_OK);
  sqlite3_bind_blob(m, 1, meta.data(), static_cast<int>(meta.size()), SQLITE_TRANSIENT);
  EXPECT_EQ(sqlite3_step(m), SQLITE_DONE);
  sqlite3_finalize(m);
  exec("COMMIT");
  sqlite3_close(db);
}

#if FRAGG_TEST_LMDB
void writeLmdbFormat1(const std::string& path, const Map& map) {
  MDB_env* env = nullptr;
  ASSERT_EQ(mdb_env_create(&env), 0);
  mdb_env_set_mapsize(env, size_t{1} << 30);
  mdb_env_set_maxdbs(env, 2);
  ASSERT_EQ(mdb_env_open(env, path.c_str(), MDB_NOSUBDIR, 0644), 0);
  MDB_txn* txn = nullptr;
  ASSERT_EQ(mdb_txn_begin(env, nullptr, 0, &txn), 0);
  MDB_dbi blocks = 0, meta = 0;
  ASSERT_EQ(mdb_dbi_open(txn, "blocks", MDB_CREATE, &blocks), 0);
  ASSERT_EQ(mdb_dbi_open(txn, "meta", MDB_CREATE, &meta), 0);
  map.forEachBlock([&](const BlockKey& k, const Block& b) {
    std::vector<uint8_t> key = recordKey(k), value = format1Record(b);
    MDB_val kv{key.size(), key.data()}, vv{value.size(), value.data()};
    EXPECT_EQ(mdb_put(txn, blocks, &kv, &vv, 0), 0);
  });
  std::vector<uint8_t> m = sampleMeta(map);
  char name[] = "map";
  MDB_val kv{3, name}, vv{m.size(), m.data()};
  EXPECT_EQ(mdb_put(txn, meta, &kv, &vv, 0), 0);
  ASSERT_EQ(mdb_txn_commit(txn), 0);
  mdb_env_close(env);
}
#endif

void expectRefusedWithTheCommand(const std::string& path, bool read_only) {
  try {
    openPageStore(path, read_only);
    FAIL() << path << ": a store of format 1 was opened";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("fragg_map convert-store " + path), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
}

TEST(StoreFormat, AStoreOfFormat1IsRefusedWithTheCommandThatConvertsItAndConvertsToTheSameMap) {
  const std::string dir = testDir();
  const Map map = sampleMap();
  ASSERT_GT(map.blockCount(), 500u);
  std::vector<std::pair<std::string, std::string>> cases = {{"/old.db", "/new.lmdb"}};
#if FRAGG_TEST_LMDB
  cases.push_back({"/old.lmdb", "/new.db"});
#endif
  for (const auto& [old_name, new_name] : cases) {
    const std::string from = dir + old_name, to = dir + new_name;
    if (old_name == "/old.db") {
      writeSqliteFormat1(from, map);
    } else {
#if FRAGG_TEST_LMDB
      writeLmdbFormat1(from, map);
#endif
    }
    if (new_name == "/new.lmdb" && !lmdbAvailable()) continue;
    expectRefusedWithTheCommand(from, /*read_only=*/true);
    expectRefusedWithTheCommand(from, /*read_only=*/false);
    // Small batches: regions are written as the slabs of format 1's z order complete.
    const ConvertStats stats = convertPageStore(from, to, /*batch_blocks=*/64);
    EXPECT_EQ(stats.blocks, map.blockCount()) << old_name;
    EXPECT_GT(stats.records, 0u);
    EXPECT_LT(stats.records * 4, stats.blocks) << "records hold regions of blocks";
    const Map back = Map::loadPageStore(*openPageStore(to, true), corridorParams());
    EXPECT_EQ(back.scanCount(), map.scanCount());
    std::string why;
    EXPECT_TRUE(sameBlocks(back, map, &why)) << old_name << ": " << why;
    // The new store is refused as a source, and an existing store as a target.
    EXPECT_THROW(convertPageStore(to, dir + "/again" + new_name), IoError);
    EXPECT_THROW(convertPageStore(from, to), IoError);
    EXPECT_EQ(Map::loadPageStore(*openPageStore(to, true), corridorParams()).blockCount(),
              map.blockCount());
  }
}

}  // namespace
}  // namespace fragg::test
