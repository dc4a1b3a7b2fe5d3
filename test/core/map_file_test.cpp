#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/internal/block_chunks.h"
#include "fragg_map/internal/scan_codec.h"
#include "fragg_map/map.h"
#include "fragg_map/map_file_format.h"
#include "legacy_map_file.h"
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
  ASSERT_EQ(a.blockCount(), b.blockCount());
  a.forEachBlock([&](const BlockKey& key, const Block& block) {
    const Block* other = b.findBlock(key);
    ASSERT_NE(other, nullptr);
    EXPECT_EQ(std::memcmp(&block, other, sizeof(Block)), 0);
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

TEST(MapFileTest, ReadsVersionOneAndFourFiles) {
  // Before version 5 the blocks were zlib'd one by one; such files still load cell for cell.
  const Map map = sampleMap();
  for (uint32_t version : {1u, 4u}) {
    const std::string path = tmpPath("v" + std::to_string(version) + ".fgm");
    test::writeLegacyMapFile(map, path, version, kMapFileCompressed);
    const Map loaded = Map::load(path);
    expectSameMaps(map, loaded);
    // Saved again, it is a current file with the same cells.
    loaded.save(tmpPath("resaved.fgm"));
    expectSameMaps(map, Map::load(tmpPath("resaved.fgm")));
    uint32_t resaved_version = 0;
    std::memcpy(&resaved_version, readAll(tmpPath("resaved.fgm")).data() + 8, 4);
    EXPECT_EQ(resaved_version, kMapFileVersion);
  }
}

// Blocks with varied cells (runs of unobserved cells, as in maps) and scattered keys.
std::vector<std::pair<BlockKey, Block>> variedBlocks(size_t n) {
  std::mt19937 rng(7);
  std::vector<std::pair<BlockKey, Block>> blocks(n);
  for (size_t i = 0; i < n; ++i) {
    blocks[i].first = {static_cast<int32_t>(i % 37) - 18, static_cast<int32_t>(i / 37) - 20,
                       static_cast<int32_t>(rng() % 5) - 2 + 10 * static_cast<int32_t>(i % 3)};
    for (int k = 0; k < kCellsPerBlock; ++k) {
      Cell& c = blocks[i].second.cells[k];
      if (rng() % 3 == 0) continue;  // unobserved
      c.hits = static_cast<int16_t>(rng() % 4);
      c.log_odds_fx = static_cast<int16_t>(static_cast<int>(rng() % 4000) - 2000);
    }
  }
  return blocks;
}

TEST(MapFileTest, BlockChunksRoundTripWithEveryCodecAndThreadCount) {
  // More blocks than one round of chunks on one thread (4 chunks of 256), a last chunk that
  // is not full, and zero blocks.
  for (ChunkCodec codec : {ChunkCodec::kZlib, ChunkCodec::kZstd}) {
    if (!chunkCodecAvailable(codec)) continue;
    for (size_t n : {size_t{0}, size_t{1}, size_t{1300}}) {
      for (int threads : {1, 2, 3}) {
        const auto blocks = variedBlocks(n);
        std::vector<BlockKey> keys;
        for (const auto& b : blocks) keys.push_back(b.first);
        ByteWriter w;
        size_t fetched = 0;
        writeBlockChunks(
            w, codec, n, keys,
            [&](size_t first, size_t count, std::vector<const Block*>& out) {
              EXPECT_EQ(first, fetched);
              fetched += count;
              for (size_t i = first; i < first + count; ++i) out.push_back(&blocks[i].second);
            },
            threads);
        EXPECT_EQ(fetched, n);
        ByteReader r(w.bytes, w.bytes.size(), "mem", "chunks");
        std::map<std::tuple<int, int, int>, Block> got;
        std::vector<BlockKey> order;
        readBlockChunks(
            r, n,
            [&](const BlockKey& k) {
              order.push_back(k);
              return &got[{k.x, k.y, k.z}];
            },
            [](const Block&) { return std::string(); }, threads);
        EXPECT_EQ(r.remaining(), 0u);
        ASSERT_EQ(order.size(), n);
        for (size_t i = 0; i < n; ++i) {
          EXPECT_EQ(order[i], keys[i]) << i;
          const Block& b = got[{keys[i].x, keys[i].y, keys[i].z}];
          ASSERT_EQ(std::memcmp(&b, &blocks[i].second, sizeof(Block)), 0)
              << chunkCodecName(codec) << " block " << i << " of " << n;
        }
      }
    }
  }
}

TEST(MapFileTest, DamagedChunksAreRejected) {
  const auto blocks = variedBlocks(300);
  std::vector<BlockKey> keys;
  for (const auto& b : blocks) keys.push_back(b.first);
  ByteWriter w;
  writeBlockChunks(w, bestChunkCodec(), blocks.size(), keys,
                   [&](size_t first, size_t count, std::vector<const Block*>& out) {
                     for (size_t i = first; i < first + count; ++i)
                       out.push_back(&blocks[i].second);
                   });
  Block sink;
  const auto anywhere = [&](const BlockKey&) { return &sink; };
  const auto fine = [](const Block&) { return std::string(); };
  const auto expectRejected = [&](std::vector<uint8_t> bytes, uint64_t count, const char* what) {
    ByteReader r(bytes, bytes.size(), "mem", "chunks");
    try {
      readBlockChunks(r, count, anywhere, fine);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  std::vector<uint8_t> bad = w.bytes;
  bad[0] = 9;  // codec
  expectRejected(bad, blocks.size(), "unknown block codec 9");
  bad = w.bytes;
  bad[16] ^= 0xff;  // inside the first chunk
  expectRejected(bad, blocks.size(), "decompress");
  expectRejected(w.bytes, blocks.size() + 256, "truncated");  // a chunk more than written
  expectRejected(w.bytes, uint64_t{1} << 40, "larger than the file");
  std::vector<uint8_t> cut(w.bytes.begin(), w.bytes.end() - 10);
  expectRejected(cut, blocks.size(), "truncated");
  // A check that fails, and a key seen twice, stop the read.
  ByteReader r(w.bytes, w.bytes.size(), "mem", "chunks");
  EXPECT_THROW(readBlockChunks(r, blocks.size(), anywhere,
                               [](const Block&) { return std::string("negative hit count"); }),
               IoError);
  ByteReader r2(w.bytes, w.bytes.size(), "mem", "chunks");
  EXPECT_THROW(readBlockChunks(
                   r2, blocks.size(), [](const BlockKey&) -> Block* { return nullptr; }, fine),
               IoError);
}

TEST(MapFileTest, KeptFloat32ScansRoundTripBitForBit) {
  // Kept scans are float32 as received by default: the file gives every point back bit for bit
  // (no returns and a point far beyond what int16 holds at any useful step too), and a map
  // loaded from it integrates (removes, corrects) exactly those points.
  MapParams p;
  p.resolution_m = 0.1;
  p.backend = Backend::kCpu;
  p.scans.keep = true;
  ASSERT_EQ(p.scans.point_step_m, 0.0);
  Map map(p);
  PointCloud c = test::roomScan(4.0, 1.0, 2.0, 16, 360);
  c.points_S[7] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  c.points_S[8] = Eigen::Vector3f(1234.5678f, -0.0001234f, 3.3333333f);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(-3.3, 2.1, 0.7);
  map.insert(c, T, SensorModel::autoFromCloud(0.0, 8.0), 42, "lidar");
  T.translation().x() += 0.35;
  map.insert(c, T, SensorModel::autoFromCloud(0.0, 8.0), 43, "lidar");
  const std::string path = tmpPath("kept_float32.fgm");
  map.save(path);
  Map loaded = Map::load(path, Backend::kCpu);
  expectSameMaps(map, loaded);
  ASSERT_EQ(loaded.scanStore().size(), 2u);
  for (ScanId id : {ScanId{0}, ScanId{1}}) {
    const EncodedPoints e = loaded.scanStore().points(id);
    EXPECT_EQ(e.step_m, 0.0);
    EXPECT_EQ(e.width, c.width);
    EXPECT_EQ(e.height, c.height);
    ASSERT_EQ(e.data.size(), c.size() * 12);
    EXPECT_EQ(0, std::memcmp(e.data.data(), c.points_S.data(), e.data.size())) << id;
  }
  // Same map, same bytes.
  loaded.save(tmpPath("kept_float32_again.fgm"));
  EXPECT_EQ(readAll(path), readAll(tmpPath("kept_float32_again.fgm")));
  // The loaded scans are the received ones: removing scan 1 leaves the map of scan 0 alone.
  MapParams plain = p;
  plain.scans.keep = false;
  Map first(plain);
  T.translation().x() -= 0.35;
  first.insert(c, T, SensorModel::autoFromCloud(0.0, 8.0));
  loaded.remove(1);
  EXPECT_EQ(loaded.knownVoxelCount(), first.knownVoxelCount());
  size_t differing = 0;
  loaded.forEachBlock([&](const BlockKey& key, const Block& block) {
    const Block* other = first.findBlock(key);
    for (int k = 0; k < kCellsPerBlock; ++k) {
      const Cell& a = block.cells[k];
      const Cell b = other ? other->cells[k] : Cell();
      differing += a.log_odds_fx != b.log_odds_fx || a.hits != b.hits;
    }
  });
  EXPECT_EQ(differing, 0u);
  // A damaged float32 scan section is rejected like any other damage.
  std::vector<char> bytes = readAll(path);
  writeAll(tmpPath("kept_float32_cut.fgm"), std::vector<char>(bytes.begin(), bytes.end() - 200));
  EXPECT_THROW(Map::load(tmpPath("kept_float32_cut.fgm")), IoError);
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
