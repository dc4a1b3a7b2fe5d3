// Writes a file atomically: everything goes to "<path>.tmp.<pid>" and is renamed over `path`
// only when complete, so readers never see a half-written file and a failed write leaves the
// old file (or none) in place.
#pragma once

#include <cstdio>
#include <string>

namespace fragg {

class AtomicFile {
 public:
  /// Opens the temporary file; throws IoError when the directory is not writable.
  explicit AtomicFile(const std::string& path);
  /// Removes the temporary file unless commit() succeeded.
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Throws IoError on a short write (disk full, I/O error).
  void write(const void* data, size_t bytes);
  void write(const std::string& s) { write(s.data(), s.size()); }
  FILE* stream() { return file_; }
  /// Flushes, closes and renames into place; throws IoError on failure.
  void commit();

 private:
  std::string path_, tmp_path_;
  FILE* file_ = nullptr;
  bool committed_ = false;
};

}  // namespace fragg
