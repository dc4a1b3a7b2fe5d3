#include "cli/map_input.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "fragg_map/errors.h"
#ifdef FRAGG_HAVE_OCTOMAP
#include "fragg_map/interop/octomap_io.h"
#endif
#ifdef FRAGG_HAVE_PAGE_STORE
#include "fragg_map/store/page_stores.h"
#endif

namespace fragg::cli {

std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (!ext.empty()) ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

fragg::Map loadMapFile(const std::string& path) {
  // Reading commands never insert: the CPU backend, no device set up.
  const Backend backend = Backend::kCpu;
  const std::string ext = extensionOf(path);
  const bool store = ext == "db" || ext == "sqlite" || ext == "lmdb" || ext == "mdb";
  if (ext != "fgm" && ext != "bt" && ext != "ot" && !store)
    throw InvalidArgument(
        fmt::format("{}: unknown map format '{}' (expected .fgm, a page store .db / .sqlite / "
                    ".lmdb / .mdb, or .bt / .ot from OctoMap)",
                    path, ext));
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw IoError(fmt::format("cannot read {}: no such file", path));
  if (std::filesystem::is_directory(path, ec))
    throw IoError(fmt::format("cannot read {}: is a directory", path));
  if (ext == "fgm") return fragg::Map::load(path, backend);
  if (store) {
#ifdef FRAGG_HAVE_PAGE_STORE
    // Read-only, one snapshot: a build may be writing the store meanwhile.
    MapParams runtime;
    runtime.backend = backend;
    return fragg::Map::loadPageStore(*openPageStore(path, /*read_only=*/true), runtime);
#else
    throw IoError(fmt::format(
        "cannot read {}: this fragg_map was built without SQLite (no page store)", path));
#endif
  }
#ifdef FRAGG_HAVE_OCTOMAP
  return fragg::importOctomap(path, backend);
#else
  throw IoError(
      fmt::format("cannot read {}: this fragg_map was built without liboctomap, so "
                  "it cannot read OctoMap files",
                  path));
#endif
}

void checkOutputDirectory(const std::string& path) {
  if (path.empty()) throw InvalidArgument("empty output path");
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw IoError(fmt::format("cannot write {}: directory {} does not exist", path, dir.string()));
  if (std::filesystem::is_directory(path, ec))
    throw IoError(fmt::format("cannot write {}: is a directory", path));
}

}  // namespace fragg::cli
