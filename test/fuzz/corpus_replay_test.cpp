// Replays the committed fuzz corpora (test/fuzz/corpus/<target>/) through the same entry
// functions libFuzzer runs. Asserts, per target: every input is read or refused with the
// project's errors (another exception fails the test, a crash ends it; CI also replays under
// ASan + UBSan, scripts/sanitize_replay.sh); every `seed_*` input (cut from real data or written
// by fragg_map, test/fuzz/make_seeds.py) parses, so a reader that refuses valid files fails;
// every `invalid_*` input (a hand-made file the reader must refuse) is refused, so a reader that
// accepts anything fails; the corpus holds at least one seed.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
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

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

}  // namespace

// The target's name in gtest's messages (instead of the struct's bytes).
void PrintTo(const Target& target, std::ostream* os) { *os << target.name; }

namespace {

class CorpusReplay : public ::testing::TestWithParam<Target> {};

TEST_P(CorpusReplay, SeedsParseInvalidInputsAreRefusedNothingElseEscapes) {
  const Target& target = GetParam();
  const fs::path dir = fs::path(FRAGG_FUZZ_CORPUS) / target.name;
  ASSERT_TRUE(fs::is_directory(dir)) << dir;
  size_t inputs = 0, parsed = 0, seeds = 0, invalid = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().filename().string();
    const std::vector<uint8_t> bytes = readBytes(entry.path());
    SCOPED_TRACE(entry.path().string());
    const bool ok = target.run(bytes.data(), bytes.size());
    ++inputs;
    parsed += ok ? 1 : 0;
    if (startsWith(name, "seed_")) {
      ++seeds;
      EXPECT_TRUE(ok) << "the real seed " << name << " of " << target.name << " was refused";
    } else if (startsWith(name, "invalid_")) {
      ++invalid;
      EXPECT_FALSE(ok) << "the invalid input " << name << " of " << target.name << " parsed";
    }
  }
  std::printf("[replay] %s: %zu inputs, %zu parsed, %zu refused (%zu seeds, %zu invalid_)\n",
              target.name.c_str(), inputs, parsed, inputs - parsed, seeds, invalid);
  // A seed corpus of a few real files and the regression inputs: never empty, never seedless.
  EXPECT_GE(inputs, 3u) << dir;
  EXPECT_GE(seeds, 1u) << dir;
}

INSTANTIATE_TEST_SUITE_P(Fuzz, CorpusReplay, ::testing::ValuesIn(targets()),
                         [](const ::testing::TestParamInfo<Target>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace fragg::fuzz
