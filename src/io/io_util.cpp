#include "io_util.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

namespace fragg {
namespace internal {

namespace fs = std::filesystem;

void throwIo(const std::string& path, const std::string& problem) {
  throw IoError(path + ": " + problem);
}

std::string readFileBytes(const std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throwIo(path, "no such file");
  if (fs::is_directory(status)) throwIo(path, "is a directory, expected a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throwIo(path, std::string("cannot open: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throwIo(path, "cannot determine the file size");
  in.seekg(0, std::ios::beg);
  std::string bytes(static_cast<size_t>(size), '\0');
  if (size > 0 && !in.read(&bytes[0], size)) throwIo(path, "read error");
  return bytes;
}

std::string lowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::string fileStem(const std::string& path) { return fs::path(path).stem().string(); }

bool naturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i]));
    const bool db = std::isdigit(static_cast<unsigned char>(b[j]));
    if (da && db) {
      size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      // Compare the runs by value: skip leading zeros, then the longer run is larger.
      size_t is = i, js = j;
      while (is + 1 < ie && a[is] == '0') ++is;
      while (js + 1 < je && b[js] == '0') ++js;
      if (ie - is != je - js) return ie - is < je - js;
      const int cmp = a.compare(is, ie - is, b, js, je - js);
      if (cmp != 0) return cmp < 0;
      if (ie - i != je - j) return ie - i < je - j;  // same value: fewer leading zeros first
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

bool isDirectory(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

bool isRegularFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

std::vector<std::string> listFiles(const std::string& dir,
                                   const std::vector<std::string>& extensions) {
  std::vector<std::string> names;
  std::error_code ec;
  fs::directory_iterator it(dir, ec);
  if (ec) throwIo(dir, "cannot list the folder: " + ec.message());
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) throwIo(dir, "cannot list the folder: " + ec.message());
    std::error_code type_ec;
    if (!it->is_regular_file(type_ec)) continue;
    const std::string name = it->path().filename().string();
    const std::string ext = lowerExtension(name);
    if (std::find(extensions.begin(), extensions.end(), ext) != extensions.end())
      names.push_back(name);
  }
  std::sort(names.begin(), names.end(), naturalLess);
  std::vector<std::string> paths;
  paths.reserve(names.size());
  for (const std::string& name : names) paths.push_back((fs::path(dir) / name).string());
  return paths;
}

std::vector<std::string> splitTokens(const std::string& line, bool commas) {
  std::vector<std::string> tokens;
  std::string current;
  for (const char c : line) {
    const bool separator = std::isspace(static_cast<unsigned char>(c)) || (commas && c == ',');
    if (separator) {
      if (!current.empty()) tokens.push_back(std::move(current));
      current.clear();
    } else {
      current.push_back(c);
    }
  }
  if (!current.empty()) tokens.push_back(std::move(current));
  return tokens;
}

bool parseDouble(const std::string& token, double* value) {
  if (token.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(token.c_str(), &end);
  if (end != token.c_str() + token.size()) return false;
  if (errno == ERANGE && std::isfinite(v) && v != 0.0) return false;
  *value = v;
  return true;
}

bool parseUint64(const std::string& token, uint64_t* value) {
  if (token.empty() || !std::isdigit(static_cast<unsigned char>(token[0]))) return false;
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(token.c_str(), &end, 10);
  if (end != token.c_str() + token.size() || errno == ERANGE) return false;
  *value = v;
  return true;
}

std::vector<TextLine> readDataLines(const std::string& path) {
  const std::string bytes = readFileBytes(path);
  std::vector<TextLine> lines;
  size_t start = 0, number = 0;
  while (start < bytes.size()) {
    size_t end = bytes.find('\n', start);
    if (end == std::string::npos) end = bytes.size();
    ++number;
    std::string text = bytes.substr(start, end - start);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const size_t first = text.find_first_not_of(" \t");
    if (first != std::string::npos && text[first] != '#') lines.push_back({text, number});
    start = end + 1;
  }
  return lines;
}

Eigen::Quaterniond checkedQuaternion(double qx, double qy, double qz, double qw,
                                     const std::string& where) {
  Eigen::Quaterniond q(qw, qx, qy, qz);
  const double norm = q.norm();
  if (!std::isfinite(norm) || norm < 0.9 || norm > 1.1) {
    std::ostringstream msg;
    msg << where << ": quaternion (x y z w) = (" << qx << " " << qy << " " << qz << " " << qw
        << ") is not a unit quaternion (norm " << norm << ")";
    throw IoError(msg.str());
  }
  q.normalize();
  return q;
}

void ByteCursor::require(size_t bytes, const char* what) const {
  if (bytes > size_ - pos_) {
    std::ostringstream msg;
    msg << "truncated " << what << " at byte " << pos_ << " (needs " << bytes << " bytes, "
        << (size_ - pos_) << " left)";
    throwIo(path_, msg.str());
  }
}

}  // namespace internal
}  // namespace fragg
