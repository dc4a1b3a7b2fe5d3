// Replays the committed fuzz corpora (test/fuzz/corpus/<target>/) through the same entry
// functions libFuzzer runs: every input must be read or refused with the project's errors (the
// entry functions catch those); another exception fails the test, a crash ends it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_targets.h"

namespace fragg::fuzz {
namespace {

namespace fs = std::filesystem;

std::vector<uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

class CorpusReplay : public ::testing::TestWithParam<Target> {};

TEST_P(CorpusReplay, EveryCommittedInputIsReadOrRefusedWithAProjectError) {
  const Target& target = GetParam();
  const fs::path dir = fs::path(FRAGG_FUZZ_CORPUS) / target.name;
  ASSERT_TRUE(fs::is_directory(dir)) << dir;
  size_t inputs = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::vector<uint8_t> bytes = readBytes(entry.path());
    SCOPED_TRACE(entry.path().string());
    EXPECT_EQ(target.run(bytes.data(), bytes.size()), 0);
    ++inputs;
  }
  // A seed corpus of a few real files and the regression inputs: never empty.
  EXPECT_GE(inputs, 3u) << dir;
}

INSTANTIATE_TEST_SUITE_P(Fuzz, CorpusReplay, ::testing::ValuesIn(targets()),
                         [](const ::testing::TestParamInfo<Target>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace fragg::fuzz
