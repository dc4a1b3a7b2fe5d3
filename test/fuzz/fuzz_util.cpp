#include "fuzz_util.h"

#include <unistd.h>
#include <zlib.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>

namespace fragg::fuzz {
namespace {

// The files this process wrote, removed at exit.
struct InputFiles {
  std::map<std::string, std::string> by_extension;
  ~InputFiles() {
    for (const auto& [ext, path] : by_extension) std::remove(path.c_str());
  }
};

}  // namespace

std::string writeInputFile(const uint8_t* data, size_t size, const std::string& extension,
                           bool append_crc) {
  static InputFiles files;
  std::string& path = files.by_extension[extension];
  if (path.empty())
    path = (std::filesystem::temp_directory_path() /
            ("fragg_fuzz_" + std::to_string(getpid()) + extension))
               .string();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  // The harness itself failing is not a finding of the reader: stop loudly.
  if (!f) throw std::runtime_error("fuzz harness: cannot write " + path);
  bool ok = size == 0 || std::fwrite(data, 1, size, f) == size;
  if (append_crc) {
    const uint32_t crc = static_cast<uint32_t>(crc32(0L, data, static_cast<uInt>(size)));
    const uint8_t footer[4] = {uint8_t(crc), uint8_t(crc >> 8), uint8_t(crc >> 16),
                               uint8_t(crc >> 24)};
    ok = ok && std::fwrite(footer, 1, 4, f) == 4;
  }
  ok = std::fclose(f) == 0 && ok;
  if (!ok) throw std::runtime_error("fuzz harness: cannot write " + path);
  return path;
}

}  // namespace fragg::fuzz
