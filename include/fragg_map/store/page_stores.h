// The page stores (fragg_map_store, an optional component: built when SQLite and zstd are
// found): LMDB, the default where it is built (faster commits and reads, docs/benchmarks.md),
// and SQLite in WAL mode. One record per block, key -> the block's cells compressed with zstd
// (with its frame checksum); one metadata record. Stores open read-only too: another process
// may read a store while a map writes it.
#pragma once

#include <memory>
#include <string>

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

}  // namespace fragg
