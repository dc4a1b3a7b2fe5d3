#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>

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

}  // namespace fragg
