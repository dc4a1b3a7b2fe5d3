#include <algorithm>
#include <cctype>
#include <filesystem>

#include "fragg_map/store/page_stores.h"

namespace fragg {

namespace {
std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}
}  // namespace

PageStoreKind pageStoreKindOf(const std::string& path) {
  return extensionOf(path) == ".lmdb" ? PageStoreKind::kLmdb : PageStoreKind::kSqlite;
}

bool isPageStorePath(const std::string& path) {
  const std::string ext = extensionOf(path);
  return ext == ".db" || ext == ".sqlite" || ext == ".lmdb";
}

std::shared_ptr<PageStore> openPageStore(const std::string& path, bool read_only) {
  return pageStoreKindOf(path) == PageStoreKind::kLmdb ? openLmdbPageStore(path, read_only)
                                                       : openSqlitePageStore(path, read_only);
}

}  // namespace fragg
