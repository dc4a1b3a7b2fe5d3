#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/map_file_format.h"
#include "test_scenes.h"

namespace fragg {
namespace {

std::string tmpPath(const std::string& name) { return std::string(FRAGG_TEST_TMP) + "/" + name; }

std::vector<char> readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeAll(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

Map sampleMap() {
  MapParams p;
  p.resolution_m = 0.1;
  p.occupancy.prob_hit = 0.65;
  p.occupancy.unknown_band = 0.02;
  Map map(p);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(-3.3, 2.1, 0.7);  // negative keys too
  map.insert(test::roomScan(4.0, 1.0, 2.0, 16, 360), T, SensorModel::autoFromCloud());
  return map;
}

void expectSameMaps(const Map& a, const Map& b) {
  EXPECT_EQ(a.resolution(), b.resolution());
  EXPECT_EQ(a.params().occupancy.prob_hit, b.params().occupancy.prob_hit);
  EXPECT_EQ(a.params().occupancy.unknown_band, b.params().occupancy.unknown_band);
  EXPECT_EQ(a.scanCount(), b.scanCount());
  ASSERT_EQ(a.blocks().size(), b.blocks().size());
  a.blocks().forEach([&](BlockIndex i) {
    const Block* other = b.blocks().findBlock(a.blocks().meta(i).key);
    ASSERT_NE(other, nullptr);
    EXPECT_EQ(std::memcmp(&a.blocks().block(i), other, sizeof(Block)), 0);
  });
}

TEST(MapFileTest, RoundTripKeepsEveryCellAndParameter) {
  const Map map = sampleMap();
  ASSERT_GT(map.knownVoxelCount(), 1000u);
  const std::string path = tmpPath("roundtrip.fgm");
  map.save(path);
  const Map loaded = Map::load(path);
  expectSameMaps(map, loaded);
  // Same map, same bytes.
  const std::string again = tmpPath("roundtrip2.fgm");
  loaded.save(again);
  EXPECT_EQ(readAll(path), readAll(again));
}

void expectRejected(const std::string& path, const std::string& fragment) {
  try {
    Map::load(path);
    ADD_FAILURE() << "loaded a bad file " << path;
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(MapFileTest, TruncatedCorruptedAndWrongVersionFilesAreRejected) {
  const std::string good = tmpPath("good.fgm");
  sampleMap().save(good);
  const std::vector<char> bytes = readAll(good);
  for (size_t cut : {size_t{0}, size_t{5}, size_t{40}, bytes.size() / 2, bytes.size() - 1}) {
    const std::string p = tmpPath("truncated.fgm");
    writeAll(p, std::vector<char>(bytes.begin(), bytes.begin() + cut));
    EXPECT_THROW(Map::load(p), IoError) << "cut at " << cut;
  }
  std::vector<char> flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x10;
  writeAll(tmpPath("flipped.fgm"), flipped);
  expectRejected(tmpPath("flipped.fgm"), "checksum");

  std::vector<char> magic = bytes;
  magic[0] = 'X';
  writeAll(tmpPath("magic.fgm"), magic);
  expectRejected(tmpPath("magic.fgm"), "magic");

  // A version this build does not know (the next one) with a valid checksum: rejected for its
  // version, not its checksum. (Version 2, the scan section, is read since issue 6.)
  std::vector<char> next = bytes;
  const uint32_t version = kMapFileVersion + 1;
  std::memcpy(next.data() + 8, &version, 4);
  const uint32_t crc = static_cast<uint32_t>(
      crc32(0L, reinterpret_cast<const Bytef*>(next.data()), next.size() - 4));
  std::memcpy(next.data() + next.size() - 4, &crc, 4);
  writeAll(tmpPath("next_version.fgm"), next);
  expectRejected(tmpPath("next_version.fgm"), "version " + std::to_string(version));

  expectRejected(tmpPath("does_not_exist.fgm"), "does_not_exist");
}

TEST(MapFileTest, FailedSaveLeavesNoFile) {
  const Map map = sampleMap();
  EXPECT_THROW(map.save("/nonexistent_dir_fragg/x.fgm"), IoError);
  // An existing file is replaced only by a complete one: a load of it still works.
  const std::string path = tmpPath("keep.fgm");
  map.save(path);
  EXPECT_NO_THROW(Map::load(path));
  EXPECT_NE(access((path + ".tmp." + std::to_string(getpid())).c_str(), F_OK), 0);
}

}  // namespace
}  // namespace fragg
