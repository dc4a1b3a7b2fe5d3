#include "fragg_map/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "fragg_map/errors.h"

namespace fragg {

AtomicFile::AtomicFile(const std::string& path)
    : path_(path), tmp_path_(path + ".tmp." + std::to_string(::getpid())) {
  if (path.empty()) throw IoError("empty output path");
  file_ = std::fopen(tmp_path_.c_str(), "wb");
  if (!file_) throw IoError("cannot write " + path + ": " + std::strerror(errno));
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!committed_) std::remove(tmp_path_.c_str());
}

void AtomicFile::write(const void* data, size_t bytes) {
  if (bytes == 0) return;
  if (!file_ || std::fwrite(data, 1, bytes, file_) != bytes)
    throw IoError("cannot write " + path_ + ": " + std::strerror(errno));
}

void AtomicFile::commit() {
  if (!file_) throw IoError("cannot write " + path_ + ": file already closed");
  const bool flushed = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!flushed || !closed) throw IoError("cannot write " + path_ + ": " + std::strerror(errno));
  if (std::rename(tmp_path_.c_str(), path_.c_str()) != 0)
    throw IoError("cannot rename " + tmp_path_ + " to " + path_ + ": " + std::strerror(errno));
  committed_ = true;
}

}  // namespace fragg
