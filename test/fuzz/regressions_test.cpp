// Inputs that broke a reader under fuzzing (test/fuzz/corpus/<target>/regress_*), each with the
// clear error the reader now gives. The corpus replay runs them too; these name the finding and
// check the message.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/internal/byte_io.h"
#include "fragg_map/internal/scan_codec.h"
#include "fragg_map/map.h"
#include "fuzz_util.h"

namespace fragg::fuzz {
namespace {

std::vector<uint8_t> corpusFile(const std::string& target, const std::string& name) {
  const std::filesystem::path path = std::filesystem::path(FRAGG_FUZZ_CORPUS) / target / name;
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << path;
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

// Found by fragg_fuzz_fgm: a compressed block of 0 bytes made ByteReader copy 0 bytes to an
// empty vector's null data() (memcpy with a null pointer: undefined behaviour, UBSan). Now the
// block is refused because it does not decompress.
TEST(FuzzRegression, FgmEmptyCompressedBlockIsRefusedClearly) {
  const std::vector<uint8_t> body = corpusFile("fgm", "regress_empty_compressed_block.fgm");
  ASSERT_FALSE(body.empty());
  const std::string path = writeInputFile(body.data(), body.size(), ".fgm", /*append_crc=*/true);
  try {
    Map::load(path, Backend::kCpu);
    FAIL() << "the map loaded";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("does not decompress"), std::string::npos) << e.what();
  }
}

// Found by fragg_fuzz_scan, the same bug in a kept-scan record (version 2, read from memory):
// "packed points size" 0 copied 0 bytes to the null data() of an empty vector. Now refused.
TEST(FuzzRegression, ScanRecordWithZeroPackedPointsIsRefusedClearly) {
  const std::vector<uint8_t> input = corpusFile("scan", "regress_zero_packed_points");
  ASSERT_GT(input.size(), 1u);
  ASSERT_EQ(input[0], 0);  // byte 0 = 0: a version-2 record in memory
  const std::vector<uint8_t> bytes(input.begin() + 1, input.end());
  ByteReader reader(bytes, bytes.size(), "regress_zero_packed_points", "scan record");
  ScanRecord record;
  EncodedPoints points;
  EXPECT_THROW(readScan(reader, record, points, 2), IoError);
}

}  // namespace
}  // namespace fragg::fuzz
