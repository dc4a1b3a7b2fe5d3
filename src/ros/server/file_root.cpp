// file_root: std::filesystem's weakly_canonical resolves `..` and the symlinks of the existing
// part of a path; the result is compared component by component with the root's real path.
#include "file_root.h"

#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "fragg_map/errors.h"

namespace fragg::ros {
namespace {

namespace fs = std::filesystem;

// `path` is `root` or lies below it (both absolute and normal).
bool startsWith(const fs::path& path, const fs::path& root) {
  auto p = path.begin();
  for (auto r = root.begin(); r != root.end(); ++r, ++p) {
    if (r->empty()) continue;  // a trailing separator of the root
    if (p == path.end() || *p != *r) return false;
  }
  return true;
}

[[noreturn]] void refuse(const std::string& requested, const std::string& root,
                         const std::string& why) {
  throw fragg::InvalidArgument("path '" + requested + "' refused: " + why +
                               " (file services read and write only under file_root '" + root +
                               "')");
}

}  // namespace

std::string prepareFileRoot(const std::string& root) {
  if (root.empty()) throw fragg::IoError("file_root is empty");
  std::error_code ec;
  fs::create_directories(root, ec);
  if (ec) throw fragg::IoError("file_root '" + root + "' cannot be created: " + ec.message());
  const fs::path real = fs::canonical(root, ec);
  if (ec) throw fragg::IoError("file_root '" + root + "': " + ec.message());
  if (!fs::is_directory(real)) throw fragg::IoError("file_root '" + root + "' is not a folder");
  return real.string();
}

std::string resolveUnderRoot(const std::string& root, const std::string& requested) {
  if (requested.empty()) throw fragg::InvalidArgument("empty path");
  const fs::path root_path(root);
  const fs::path asked(requested);
  const fs::path lexical = (asked.is_absolute() ? asked : root_path / asked).lexically_normal();
  // A dangling symlink on the way would be followed by a later write (or its target created).
  fs::path prefix;
  for (const fs::path& part : lexical) {
    prefix /= part;
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(prefix, ec)) && !fs::exists(prefix, ec))
      refuse(requested, root, "'" + prefix.string() + "' is a symbolic link to nothing");
  }
  std::error_code ec;
  const fs::path real = fs::weakly_canonical(lexical, ec);
  if (ec) refuse(requested, root, ec.message());
  if (!startsWith(real, root_path)) {
    const bool lexically_inside = startsWith(lexical, root_path);
    refuse(requested, root,
           lexically_inside      ? "a symbolic link leads to '" + real.string() + "', outside"
           : asked.is_absolute() ? "an absolute path outside"
                                 : "'..' leads to '" + real.string() + "', outside");
  }
  if (real == root_path || real.lexically_relative(root_path) == ".")
    refuse(requested, root, "names the folder itself, not a file in it");
  return real.string();
}

}  // namespace fragg::ros
