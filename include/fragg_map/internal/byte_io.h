// Little-endian byte buffers for the binary files (.fgm maps, spilled scans): a writer that
// appends plain values and a bounds-checked reader that names what it was reading when the
// bytes ran out.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fragg_map/errors.h"

namespace fragg {

class ByteWriter {
 public:
  template <class T>
  void put(const T& v) {
    put(&v, sizeof(T));
  }
  void put(const void* data, size_t n) {
    if (n == 0) return;
    const size_t at = bytes.size();
    bytes.resize(at + n);
    std::memcpy(bytes.data() + at, data, n);
  }
  std::vector<uint8_t> bytes;
};

/// Reads bytes [begin, end) of a buffer; every failure throws IoError("<path>: <what>: ...").
class ByteReader {
 public:
  ByteReader(const std::vector<uint8_t>& b, size_t end, std::string path, std::string what)
      : bytes_(b), end_(end), path_(std::move(path)), what_(std::move(what)) {}
  template <class T>
  T get(const char* field) {
    T v;
    take(&v, sizeof(T), field);
    return v;
  }
  void take(void* out, size_t n, const char* field) {
    if (end_ - pos_ < n) fail(std::string("truncated while reading ") + field);
    if (n == 0) return;  // `out` may be null then (an empty vector's data()): no memcpy
    std::memcpy(out, bytes_.data() + pos_, n);
    pos_ += n;
  }
  /// The next n bytes in place (valid while the buffer lives), skipped over.
  const uint8_t* view(size_t n, const char* field) {
    if (end_ - pos_ < n) fail(std::string("truncated while reading ") + field);
    const uint8_t* at = bytes_.data() + pos_;
    pos_ += n;
    return at;
  }
  size_t remaining() const { return end_ - pos_; }
  [[noreturn]] void fail(const std::string& why) const {
    throw IoError(path_ + ": " + what_ + ": " + why);
  }

 private:
  const std::vector<uint8_t>& bytes_;
  size_t end_;
  size_t pos_ = 0;
  std::string path_;
  std::string what_;
};

/// The whole file; IoError when it cannot be opened or read.
std::vector<uint8_t> readWholeFile(const std::string& path);

}  // namespace fragg
