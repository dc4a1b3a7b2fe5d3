// Helpers for the dataset-reader tests: per-test scratch folders, raw file access, error checks.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <iterator>
#include <string>
#include <vector>

#include "fragg_map/errors.h"

namespace fragg {
namespace test {

inline std::string realData(const std::string& relative) {
  return std::string(FRAGG_REAL_DATA) + "/" + relative;
}

/// A fresh, empty folder for the running test (tests may run in parallel processes).
inline std::string scratchDir() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string dir =
      std::string(FRAGG_TEST_TMP) + "/io/" + info->test_suite_name() + "." + info->name();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << "cannot read " << path;
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << "cannot write " << path;
}

template <typename T>
std::string rawBytes(const T& value) {
  return std::string(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
T loadAt(const std::string& bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

/// Byte offset of the first byte after `marker` (e.g. "end_header\n"); fails the test if absent.
inline size_t offsetAfter(const std::string& bytes, const std::string& marker) {
  const size_t pos = bytes.find(marker);
  EXPECT_NE(pos, std::string::npos) << "no '" << marker << "'";
  return pos == std::string::npos ? 0 : pos + marker.size();
}

/// LZF stream made only of literal runs (valid input for any LZF decoder).
inline std::string lzfLiterals(const std::string& data) {
  std::string out;
  for (size_t i = 0; i < data.size(); i += 32) {
    const size_t run = std::min<size_t>(32, data.size() - i);
    out.push_back(static_cast<char>(run - 1));
    out.append(data, i, run);
  }
  return out;
}

/// Runs `fn`, expects a fragg::IoError whose message contains every one of `needles`.
inline void expectIoError(const std::function<void()>& fn,
                          std::initializer_list<std::string> needles) {
  try {
    fn();
    ADD_FAILURE() << "expected fragg::IoError, nothing was thrown";
  } catch (const IoError& e) {
    const std::string what = e.what();
    for (const std::string& needle : needles)
      EXPECT_NE(what.find(needle), std::string::npos)
          << "message '" << what << "' lacks '" << needle << "'";
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected fragg::IoError, got another exception: " << e.what();
  }
}

/// Runs `fn` on damaged input: succeeding or throwing IoError are both fine, anything else
/// (another exception type, a crash) is a failure.
inline void expectParsesOrIoError(const std::function<void()>& fn, const std::string& context) {
  try {
    fn();
  } catch (const IoError&) {
  } catch (const std::exception& e) {
    ADD_FAILURE() << context << ": unexpected exception " << e.what();
  }
}

}  // namespace test
}  // namespace fragg
