// Internal helpers shared by the dataset readers: whole-file reads, bounds-checked binary
// decoding, text tokenising, natural file ordering. Every failure is an IoError naming the path.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "fragg_map/errors.h"

namespace fragg {
namespace internal {

/// Throws IoError("<path>: <problem>").
[[noreturn]] void throwIo(const std::string& path, const std::string& problem);

/// Reads a whole file; throws IoError when it is missing, a directory or unreadable.
std::string readFileBytes(const std::string& path);

/// Lower-case extension with the dot (".pcd"), "" when there is none.
std::string lowerExtension(const std::string& path);

/// File name without folder and without the last extension ("000012" for ".../000012.bin").
std::string fileStem(const std::string& path);

/// "file10" after "file9": digit runs compare by value, everything else by character.
bool naturalLess(const std::string& a, const std::string& b);

/// Regular files directly in `dir` whose lower-case extension is one of `extensions`, in
/// natural order of their names. Throws IoError when `dir` cannot be listed.
std::vector<std::string> listFiles(const std::string& dir,
                                   const std::vector<std::string>& extensions);

bool isDirectory(const std::string& path);
bool isRegularFile(const std::string& path);

/// Splits at ASCII whitespace (and commas when `commas` is true), dropping empty tokens.
std::vector<std::string> splitTokens(const std::string& line, bool commas = false);

/// Parses a whole token as a double ("nan" and "inf" included); false when it is not one.
bool parseDouble(const std::string& token, double* value);
/// Parses a whole token as a non-negative integer; false when it is not one.
bool parseUint64(const std::string& token, uint64_t* value);

/// Text lines of a file with '\r' stripped; `line_numbers` are 1-based.
struct TextLine {
  std::string text;
  size_t number = 0;
};
/// Non-empty lines that do not start with '#' (after leading whitespace).
std::vector<TextLine> readDataLines(const std::string& path);

/// Rotation from a quaternion given as x y z w; throws IoError (naming `where`) when it is not
/// finite or far from unit length (|q| outside [0.9, 1.1]); normalises otherwise.
Eigen::Quaterniond checkedQuaternion(double qx, double qy, double qz, double qw,
                                     const std::string& where);

/// A bounds-checked little/big-endian cursor over a byte buffer.
class ByteCursor {
 public:
  ByteCursor(const char* data, size_t size, const std::string& path)
      : data_(data), size_(size), path_(path) {}

  size_t position() const { return pos_; }
  size_t remaining() const { return size_ - pos_; }
  const char* current() const { return data_ + pos_; }
  const std::string& path() const { return path_; }

  /// Throws IoError("<path>: truncated <what> ...") when fewer than `bytes` remain.
  void require(size_t bytes, const char* what) const;
  void skip(size_t bytes, const char* what) {
    require(bytes, what);
    pos_ += bytes;
  }
  void seek(size_t position) { pos_ = position <= size_ ? position : size_; }

  template <typename T>
  T read(const char* what, bool big_endian = false) {
    require(sizeof(T), what);
    T value;
    std::memcpy(&value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    if (big_endian) value = byteSwap(value);
    return value;
  }

  template <typename T>
  static T byteSwap(T value) {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }

 private:
  const char* data_;
  size_t size_;
  size_t pos_ = 0;
  std::string path_;
};

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the binary readers and writers assume a little-endian host");

}  // namespace internal
}  // namespace fragg
