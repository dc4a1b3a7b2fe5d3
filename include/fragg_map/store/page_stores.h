// The page stores (fragg_map_store, an optional component: built when SQLite and zstd are
// found): LMDB, the default where it is built (faster commits and reads, docs/benchmarks.md),
// and SQLite in WAL mode. One record per region of 4x4x4 blocks (store format 2, page_store.h),
// each block compressed with zstd (with its frame checksum) or one value when uniform; one
// metadata record. Stores open read-only too: another process may read a store while a map
// writes it. A store of format 1 (one record per block) is refused on open, with the command
// that converts it (`fragg_map convert-store`, convertPageStore).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "fragg_map/page_store.h"

namespace fragg {

enum class PageStoreKind { kSqlite, kLmdb };

/// Opens (read_only: never creates) or creates a store. IoError when it cannot be opened, is
/// not a fragg_map store, or (read-only) does not exist.
std::shared_ptr<PageStore> openSqlitePageStore(const std::string& path, bool read_only);
/// InvalidArgument when this build has no LMDB (lmdbAvailable()).
std::shared_ptr<PageStore> openLmdbPageStore(const std::string& path, bool read_only);
bool lmdbAvailable();

/// LMDB when this build has it, else SQLite.
PageStoreKind defaultPageStoreKind();
/// An existing file: SQLite by its header, else LMDB. A new one by its extension (.db, .sqlite:
/// SQLite; .lmdb, .mdb: LMDB), any other extension the default kind.
PageStoreKind pageStoreKindOf(const std::string& path);
/// Whether the extension is one of a page store's (.db, .sqlite, .lmdb, .mdb).
bool isPageStorePath(const std::string& path);
std::shared_ptr<PageStore> openPageStore(const std::string& path, bool read_only);

/// A store of format 1 (one record per block) read whole from one snapshot: fn(key, block)
/// for each block; returns its metadata record. IoError when it is not a store of format 1.
std::vector<uint8_t> readSqliteFormat1(
    const std::string& path, const std::function<void(const BlockKey&, const Block&)>& fn);
std::vector<uint8_t> readLmdbFormat1(const std::string& path,
                                     const std::function<void(const BlockKey&, const Block&)>& fn);

struct ConvertStats {
  uint64_t blocks = 0;   ///< blocks read and written
  uint64_t records = 0;  ///< region records written
};
/// Writes the map of `from` (a store of format 1, of either kind) into `to`, a new store of
/// this build's format (its kind by pageStoreKindOf), in commits of at most `batch_blocks`
/// blocks; the metadata goes with the last. IoError when `from` is not a store of format 1 or
/// `to` exists.
ConvertStats convertPageStore(const std::string& from, const std::string& to,
                              size_t batch_blocks = 200000);

}  // namespace fragg
