// .fgm: the region section (since version 4) round trip; version 3 and 4 files are still read.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../core/legacy_map_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/map_file_format.h"
#include "submap_scenes.h"

namespace fragg {
namespace {

std::string tmpPath(const std::string& name) { return std::string(FRAGG_TEST_TMP) + "/" + name; }

std::vector<uint8_t> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

uint32_t versionOf(const std::string& path) {
  uint32_t v = 0;
  std::memcpy(&v, readBytes(path).data() + 8, 4);
  return v;
}

TEST(SubmapFileTest, BoxRegionRoundTrips) {
  Map map = test::roomMap();
  SubmapRegion box =
      SubmapRegion::box(Eigen::Vector3d(-1.03, -2.0, -0.5), Eigen::Vector3d(2.5, 1.01, 1.5));
  Map sub = map.truncate(box.min_map, box.max_map);
  box.frame_id = "robot_2/map";
  sub.setRegion(box);
  const std::string path = tmpPath("sub_box.fgm");
  sub.save(path);
  EXPECT_EQ(versionOf(path), kMapFileVersion);
  const Map back = Map::load(path, Backend::kCpu);
  EXPECT_EQ(back.region().kind, SubmapRegion::Kind::kBox);
  EXPECT_EQ(back.region().min_map, box.min_map);
  EXPECT_EQ(back.region().max_map, box.max_map);
  EXPECT_EQ(back.region().frame_id, "robot_2/map");
  std::string why;
  EXPECT_TRUE(test::sameCells(back, sub, &why)) << why;
}

TEST(SubmapFileTest, SphereRegionRoundTripsAndWholeMapHasNone) {
  Map map = test::roomMap();
  const Map sub = map.truncateOutside(Eigen::Vector3d(0.5, 0.2, 0.1), 2.25);
  sub.save(tmpPath("sub_sphere.fgm"));
  const Map back = Map::load(tmpPath("sub_sphere.fgm"), Backend::kCpu);
  EXPECT_EQ(back.region().kind, SubmapRegion::Kind::kOutsideSphere);
  EXPECT_EQ(back.region().center_map, Eigen::Vector3d(0.5, 0.2, 0.1));
  EXPECT_EQ(back.region().radius_m, 2.25);
  EXPECT_EQ(back.region().frame_id, "map");
  EXPECT_TRUE(test::sameCells(back, sub));
  map.save(tmpPath("rest.fgm"));
  EXPECT_TRUE(Map::load(tmpPath("rest.fgm"), Backend::kCpu).region().empty());
}

TEST(SubmapFileTest, ReadsVersionThreeAndFourFiles) {
  const Map map = test::roomMap();
  const std::string path = tmpPath("v3.fgm");
  test::writeLegacyMapFile(map, path, 3, kMapFileCompressed);
  const Map back = Map::load(path, Backend::kCpu);
  EXPECT_TRUE(back.region().empty());
  std::string why;
  EXPECT_TRUE(test::sameCells(back, map, &why)) << why;
  // A version 3 file cannot carry a region; a version 4 file can.
  Map cut = test::roomMap();
  const Map sub = cut.truncateOutside(Eigen::Vector3d(0.5, 0.2, 0.1), 2.25);
  test::writeLegacyMapFile(sub, path, 3, kMapFileCompressed | kMapFileRegion);
  EXPECT_THROW(Map::load(path, Backend::kCpu), IoError);
  test::writeLegacyMapFile(sub, path, 4, kMapFileCompressed | kMapFileRegion);
  const Map sub_back = Map::load(path, Backend::kCpu);
  EXPECT_EQ(sub_back.region().kind, SubmapRegion::Kind::kOutsideSphere);
  EXPECT_EQ(sub_back.region().radius_m, 2.25);
  EXPECT_TRUE(test::sameCells(sub_back, sub, &why)) << why;
}

TEST(SubmapFileTest, CorruptRegionIsRejected) {
  Map map = test::roomMap();
  const Map sub = map.truncate(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  const std::string path = tmpPath("bad_region.fgm");
  sub.save(path);
  std::vector<uint8_t> bytes = readBytes(path);
  // Flip one byte of the file: the checksum catches it.
  bytes[bytes.size() / 2] ^= 0x5a;
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  EXPECT_THROW(Map::load(path, Backend::kCpu), IoError);
  // setRegion validates as the loader does.
  SubmapRegion inverted;
  inverted.kind = SubmapRegion::Kind::kBox;
  inverted.min_map = Eigen::Vector3d::Ones();
  Map plain(test::cpuParams());
  EXPECT_THROW(plain.setRegion(inverted), InvalidArgument);
  EXPECT_TRUE(plain.region().empty());
}

}  // namespace
}  // namespace fragg
