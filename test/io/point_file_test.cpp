// Point-file readers and writers: the real scans of ../shared/data/real, hand-made files for
// every encoding, round trips, and damaged files (which must give IoError, never a crash).
#include "fragg_map/io/point_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "io_test_util.h"

namespace fragg {
namespace {

using test::expectIoError;
using test::expectParsesOrIoError;
using test::loadAt;
using test::rawBytes;
using test::readBytes;
using test::realData;
using test::scratchDir;
using test::writeBytes;

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

size_t countNan(const PointCloud& cloud) {
  return static_cast<size_t>(std::count_if(cloud.points_S.begin(), cloud.points_S.end(),
                                           [](const Eigen::Vector3f& p) { return p.hasNaN(); }));
}

// Range statistics over finite points.
struct Ranges {
  size_t finite = 0;
  double min_m = INFINITY;
  double max_m = 0.0;
};
Ranges ranges(const PointCloud& cloud) {
  Ranges r;
  for (const Eigen::Vector3f& p : cloud.points_S) {
    if (!p.allFinite()) continue;
    ++r.finite;
    r.min_m = std::min(r.min_m, static_cast<double>(p.norm()));
    r.max_m = std::max(r.max_m, static_cast<double>(p.norm()));
  }
  return r;
}

void expectSamePoint(const Eigen::Vector3f& a, const Eigen::Vector3f& b, size_t index) {
  if (a.hasNaN() || b.hasNaN()) {
    EXPECT_TRUE(a.hasNaN() && b.hasNaN())
        << "point " << index << ": " << a.transpose() << " vs " << b.transpose();
  } else {
    EXPECT_EQ(a, b) << "point " << index;
  }
}

// ---------------------------------------------------------------- real data

TEST(PlyReal, SmallGicpScansHaveTheDocumentedCountsAndNoReturns) {
  struct Expected {
    const char* file;
    size_t points;
    size_t zeros;
  };
  double max_range_m = 0.0;  // over both scans: 78 m
  for (const Expected& e :
       {Expected{"source.ply", 69792, 5107}, Expected{"target.ply", 69088, 5032}}) {
    const std::string path = realData(std::string("small_gicp_pair/") + e.file);
    const PointCloud cloud = readPly(path);
    EXPECT_EQ(cloud.size(), e.points) << path;
    EXPECT_EQ(countNan(cloud), e.zeros) << path;  // (0,0,0) = no return -> NaN
    EXPECT_FALSE(cloud.organised());
    const Ranges r = ranges(cloud);
    EXPECT_EQ(r.finite, e.points - e.zeros);
    EXPECT_GT(r.min_m, 1.5);
    EXPECT_LT(r.min_m, 2.5);
    EXPECT_GT(r.max_m, 40.0);
    EXPECT_LT(r.max_m, 80.0);
    max_range_m = std::max(max_range_m, r.max_m);
    // Independent check of a few records: float x y z intensity after end_header.
    const std::string bytes = readBytes(path);
    const size_t data = test::offsetAfter(bytes, "end_header\n");
    for (size_t i : {size_t{0}, size_t{1234}, e.points / 2, e.points - 1}) {
      const Eigen::Vector3f raw(loadAt<float>(bytes, data + 16 * i),
                                loadAt<float>(bytes, data + 16 * i + 4),
                                loadAt<float>(bytes, data + 16 * i + 8));
      expectSamePoint(cloud.points_S[i], raw.isZero() ? Eigen::Vector3f::Constant(kNan) : raw, i);
    }
  }
  EXPECT_GT(max_range_m, 75.0);
}

TEST(PcdReal, NebulaScansHaveTheDocumentedCounts) {
  struct Expected {
    const char* file;
    size_t points;
    double max_range_m;  // upper bound
  };
  const Expected expected[] = {{"vlp16_1673400472138016708.pcd", 14831, 130.0},
                               {"vlp32_1713492677464078412.pcd", 26216, 250.0},
                               {"vls128_1585897255376374245.pcd", 208680, 260.0},
                               {"64_1673403880898440686.pcd", 93591, 250.0},
                               {"xt32_1673400678101968885.pcd", 63021, 150.0},
                               {"qt128_1730273789174759609.pcd", 73560, 100.0}};
  for (const Expected& e : expected) {
    const std::string path = realData(std::string("nebula_single_scans/") + e.file);
    Eigen::Isometry3d T_file_sensor;
    const PointCloud cloud = readPcd(path, &T_file_sensor);
    EXPECT_EQ(cloud.size(), e.points) << path;
    EXPECT_TRUE(T_file_sensor.isApprox(Eigen::Isometry3d::Identity())) << path;
    const Ranges r = ranges(cloud);
    EXPECT_EQ(r.finite, e.points) << path;
    EXPECT_GT(r.max_m, 5.0) << path;
    EXPECT_LT(r.max_m, e.max_range_m) << path;
    EXPECT_EQ(readPointFile(path).size(), e.points);
  }
  // VLS-128: outdoor, up to 239 m.
  const Ranges vls =
      ranges(readPcd(realData("nebula_single_scans/vls128_1585897255376374245.pcd")));
  EXPECT_GT(vls.max_m, 200.0);
}

TEST(PcdReal, ExtraFieldsAreSkippedByOffset) {
  // VLP-16: x y z intensity(U1) return_type(U1) channel(U2) azimuth elevation distance(F4)
  // time_stamp(U4): the stored distance must be the norm of the x y z we read.
  const std::string path = realData("nebula_single_scans/vlp16_1673400472138016708.pcd");
  const PointCloud cloud = readPcd(path);
  const std::string bytes = readBytes(path);
  const size_t data = test::offsetAfter(bytes, "DATA binary\n");
  ASSERT_EQ(bytes.size() - data, cloud.size() * 32);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const float distance = loadAt<float>(bytes, data + 32 * i + 24);
    ASSERT_NEAR(cloud.points_S[i].norm(), distance, 1e-3) << "point " << i;
  }
}

TEST(PcdReal, PclRoomScansAreBinaryCompressed) {
  for (const auto& [file, count] : {std::pair<const char*, size_t>{"room_scan1.pcd", 112586},
                                    std::pair<const char*, size_t>{"room_scan2.pcd", 112624}}) {
    const std::string path = realData(std::string("pcl_room_scans/") + file);
    ASSERT_NE(readBytes(path).find("DATA binary_compressed"), std::string::npos);
    const PointCloud cloud = readPcd(path);
    EXPECT_EQ(cloud.size(), count) << path;
    const Ranges r = ranges(cloud);
    EXPECT_EQ(r.finite, count);
    // Indoor: a garbled decompression would give huge or denormal coordinates.
    EXPECT_LT(r.max_m, 30.0);
    EXPECT_GT(r.max_m, 3.0);
  }
  // The two scans overlap: their centroids are close.
  auto centroid = [](const PointCloud& c) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3f& p : c.points_S) sum += p.cast<double>();
    return Eigen::Vector3d(sum / static_cast<double>(c.size()));
  };
  const Eigen::Vector3d c1 = centroid(readPcd(realData("pcl_room_scans/room_scan1.pcd")));
  const Eigen::Vector3d c2 = centroid(readPcd(realData("pcl_room_scans/room_scan2.pcd")));
  EXPECT_LT((c1 - c2).norm(), 2.0);
}

TEST(XyzReal, OctomapScanDat) {
  const std::string dir = scratchDir();
  const std::string path = dir + "/scan.dat";
  const std::string command =
      "bunzip2 -c '" + realData("octomap/scan.dat.bz2") + "' > '" + path + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const PointCloud cloud = readXyz(path);
  EXPECT_EQ(cloud.size(), 88206u);
  const Ranges r = ranges(cloud);
  EXPECT_EQ(r.finite, 88206u);
  EXPECT_NEAR(r.min_m, 0.47, 0.02);
  EXPECT_NEAR(r.max_m, 29.0, 1.0);
  EXPECT_EQ(cloud.points_S[0], Eigen::Vector3f(-0.0434742f, -4.82982f, 0.499645f));
  EXPECT_EQ(readPointFile(path).size(), 88206u);
  expectIoError([&] { readPointFile(realData("octomap/scan.dat.bz2")); },
                {"scan.dat.bz2", "decompress"});
}

// ---------------------------------------------------------------- PCD encodings

TEST(Pcd, AsciiOrganisedWithNanAndExtraFields) {
  const std::string path = scratchDir() + "/organised.pcd";
  writeBytes(path,
             "# .PCD v0.7 - Point Cloud Data file format\r\n"
             "VERSION 0.7\r\nFIELDS intensity x y z normal\r\nSIZE 1 4 8 4 4\r\n"
             "TYPE U F F F F\r\nCOUNT 1 1 1 1 3\r\nWIDTH 3\r\nHEIGHT 2\r\n"
             "VIEWPOINT 0 0 0 1 0 0 0\r\nPOINTS 6\r\nDATA ascii\r\n"
             "7 1 2 3 0 0 1\r\n"
             "7 nan nan nan 0 0 1\r\n"
             "7 -1.5 2.25 1e-3 0 0 1\r\n"
             "\n"
             "7 4 5 6 0 0 1\n"
             "7 7 8 9 0 0 1\n"
             "7 NaN NaN NaN 0 0 1\n");
  const PointCloud cloud = readPcd(path);
  ASSERT_EQ(cloud.size(), 6u);
  EXPECT_TRUE(cloud.organised());
  EXPECT_EQ(cloud.width, 3u);
  EXPECT_EQ(cloud.height, 2u);
  EXPECT_EQ(cloud.points_S[0], Eigen::Vector3f(1, 2, 3));
  EXPECT_TRUE(cloud.points_S[1].hasNaN());
  EXPECT_EQ(cloud.points_S[2], Eigen::Vector3f(-1.5f, 2.25f, 1e-3f));
  EXPECT_EQ(cloud.points_S[4], Eigen::Vector3f(7, 8, 9));
  EXPECT_TRUE(cloud.points_S[5].hasNaN());
}

// A binary PCD: x y z as F8, a padding field and a U2 field between them.
std::string binaryF8Pcd(const std::vector<Eigen::Vector3d>& points) {
  std::string s =
      "VERSION .7\nFIELDS x _ ring y z\nSIZE 8 4 2 8 8\nTYPE F U U F F\nCOUNT 1 1 1 1 1\n"
      "WIDTH " +
      std::to_string(points.size()) + "\nHEIGHT 1\nPOINTS " + std::to_string(points.size()) +
      "\nDATA binary\n";
  for (const Eigen::Vector3d& p : points) {
    s += rawBytes(p.x()) + std::string(4, '\xAB') + rawBytes(uint16_t{12}) + rawBytes(p.y()) +
         rawBytes(p.z());
  }
  return s;
}

TEST(Pcd, BinaryDoubleXyzWithPadding) {
  const std::string path = scratchDir() + "/f8.pcd";
  const std::vector<Eigen::Vector3d> points = {{1.0, -2.0, 3.5}, {1e3, 0.125, -7.0}, {0, 0, 0}};
  writeBytes(path, binaryF8Pcd(points));
  const PointCloud cloud = readPcd(path);
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_FALSE(cloud.organised());
  for (size_t i = 0; i < points.size(); ++i) EXPECT_EQ(cloud.points_S[i], points[i].cast<float>());
}

// binary_compressed: fields are stored one after the other (all x, all y, ...).
std::string compressedPcdHeader(uint32_t width, uint32_t height) {
  return "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
         "WIDTH " +
         std::to_string(width) + "\nHEIGHT " + std::to_string(height) +
         "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(width * height) +
         "\nDATA binary_compressed\n";
}

TEST(Pcd, BinaryCompressedOrganisedLiteralRuns) {
  const uint32_t width = 5, height = 3, n = width * height;
  std::vector<Eigen::Vector3f> points(n);
  std::string columns[4];
  for (uint32_t i = 0; i < n; ++i) {
    points[i] = i % 4 == 1 ? Eigen::Vector3f::Constant(kNan)
                           : Eigen::Vector3f(0.5f * i, -1.0f * i, 100.0f + i);
    for (int axis = 0; axis < 3; ++axis) columns[axis] += rawBytes(points[i][axis]);
    columns[3] += rawBytes(static_cast<float>(i * 10));
  }
  const std::string raw = columns[0] + columns[1] + columns[2] + columns[3];
  const std::string lzf = test::lzfLiterals(raw);
  const std::string path = scratchDir() + "/compressed.pcd";
  writeBytes(path, compressedPcdHeader(width, height) + rawBytes(uint32_t(lzf.size())) +
                       rawBytes(uint32_t(raw.size())) + lzf);
  const PointCloud cloud = readPcd(path);
  ASSERT_EQ(cloud.size(), n);
  EXPECT_EQ(cloud.width, width);
  EXPECT_EQ(cloud.height, height);
  for (uint32_t i = 0; i < n; ++i) expectSamePoint(cloud.points_S[i], points[i], i);
}

TEST(Pcd, BinaryCompressedBackReferences) {
  // 12 points, every value 1.5f: 192 bytes = a 4-byte literal, then one long back reference
  // (offset 4, length 188 = 2 + 7 + 179) that overlaps the bytes it writes.
  const uint32_t n = 12;
  std::string lzf;
  lzf.push_back(3);
  lzf += rawBytes(1.5f);
  lzf.push_back(static_cast<char>(0xE0));  // length 7 + extra, offset high bits 0
  lzf.push_back(static_cast<char>(179));   // extra length
  lzf.push_back(static_cast<char>(3));     // offset low bits: 3 + 1 = 4 bytes back
  const std::string path = scratchDir() + "/backref.pcd";
  writeBytes(path, compressedPcdHeader(n, 1) + rawBytes(uint32_t(lzf.size())) +
                       rawBytes(uint32_t(n * 16)) + lzf);
  const PointCloud cloud = readPcd(path);
  ASSERT_EQ(cloud.size(), n);
  for (const Eigen::Vector3f& p : cloud.points_S) EXPECT_EQ(p, Eigen::Vector3f::Constant(1.5f));

  // The same stream with the reference pointing before the start of the output.
  std::string bad = lzf;
  bad[bad.size() - 1] = static_cast<char>(9);
  writeBytes(path, compressedPcdHeader(n, 1) + rawBytes(uint32_t(bad.size())) +
                       rawBytes(uint32_t(n * 16)) + bad);
  expectIoError([&] { readPcd(path); }, {path, "corrupted LZF"});
  // A stream that decodes to fewer bytes than announced.
  writeBytes(path, compressedPcdHeader(n, 1) + rawBytes(uint32_t(5)) + rawBytes(uint32_t(n * 16)) +
                       lzf.substr(0, 5));
  expectIoError([&] { readPcd(path); }, {path, "corrupted LZF"});
  // Sizes that do not match the header.
  writeBytes(path, compressedPcdHeader(n, 1) + rawBytes(uint32_t(lzf.size())) +
                       rawBytes(uint32_t(n * 16 - 4)) + lzf);
  expectIoError([&] { readPcd(path); }, {path, "uncompressed size"});
  writeBytes(path, compressedPcdHeader(n, 1) + rawBytes(uint32_t(lzf.size() + 100)) +
                       rawBytes(uint32_t(n * 16)) + lzf);
  expectIoError([&] { readPcd(path); }, {path, "truncated"});
}

TEST(Pcd, ViewpointGivesSensorFramePointsAndThePose) {
  // Sensor at (1, 2, 3) turned 90 degrees about z: VIEWPOINT tx ty tz qw qx qy qz.
  const double h = std::sqrt(0.5);
  const std::string path = scratchDir() + "/viewpoint.pcd";
  writeBytes(path,
             "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
             "HEIGHT 1\nVIEWPOINT 1 2 3 " +
                 std::to_string(h) + " 0 0 " + std::to_string(h) +
                 "\nPOINTS 2\nDATA ascii\n1 3 3\n1 2 4\n");
  Eigen::Isometry3d T_file_sensor;
  const PointCloud cloud = readPcd(path, &T_file_sensor);
  EXPECT_TRUE(T_file_sensor.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(T_file_sensor.linear().isApprox(
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-6));
  ASSERT_EQ(cloud.size(), 2u);
  // (1,3,3) is 1 m along the file's +y from the sensor = the sensor's +x.
  EXPECT_TRUE(cloud.points_S[0].isApprox(Eigen::Vector3f(1, 0, 0), 1e-5))
      << cloud.points_S[0].transpose();
  EXPECT_TRUE(cloud.points_S[1].isApprox(Eigen::Vector3f(0, 0, 1), 1e-5))
      << cloud.points_S[1].transpose();
}

TEST(Pcd, CorruptedHeadersAreRejectedWithTheProblem) {
  const std::string path = scratchDir() + "/bad.pcd";
  const std::string fields = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  struct Case {
    std::string text;
    std::string needle;
  };
  const Case cases[] = {
      {"", "empty file"},
      {"ply\nformat ascii 1.0\n", "not a PCD file"},
      {"hello world\n", "wrong magic"},
      {"VERSION 0.7\n" + fields + "WIDTH 1\nHEIGHT 1\nPOINTS 1\n", "no DATA line"},
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "SIZE has 2"},
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F Q\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "TYPE 'Q'"},
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F U\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "field z must be F"},
      {"VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2\n",
       "no z field"},
      {"VERSION 0.7\n" + fields + "WIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n", "POINTS 3"},
      {"VERSION 0.7\n" + fields + "WIDTH two\nPOINTS 3\nDATA ascii\n", "WIDTH"},
      {"VERSION 0.7\n" + fields + "WIDTH 1\nPOINTS 1\nDATA lzma\n", "unknown encoding"},
      {"VERSION 0.7\n" + fields + "WIDTH 1\nVIEWPOINT 0 0 0 0 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "not a unit quaternion"},
      {"VERSION 0.7\n" + fields + "WIDTH 1\nPOINTS 1\nCOLOUR red\nDATA ascii\n1 2 3\n",
       "unknown header keyword"},
      {"VERSION 0.7\n" + fields + "WIDTH 2\nPOINTS 2\nDATA ascii\n1 2 3\n4 5\n", "too few values"},
      {"VERSION 0.7\n" + fields + "WIDTH 2\nPOINTS 2\nDATA ascii\n1 2 3\n4 five 6\n",
       "'five' is not a number"},
      {"VERSION 0.7\n" + fields + "WIDTH 3\nPOINTS 3\nDATA ascii\n1 2 3\n", "truncated"},
      {"VERSION 0.7\n" + fields + "WIDTH 4\nPOINTS 4\nDATA binary\n" + std::string(40, '\0'),
       "truncated PCD binary data"},
      {"VERSION 0.7\n" + fields + "WIDTH 4000000000\nHEIGHT 4000000000\nDATA binary\n",
       "do not fit"},
      {"VERSION 0.7\n" + fields + "WIDTH 9223372036854775808\nHEIGHT 4\nDATA binary\n",
       "overflows"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.needle);
    writeBytes(path, c.text);
    expectIoError([&] { readPcd(path); }, {path, c.needle});
  }
}

// ---------------------------------------------------------------- PLY encodings

TEST(Ply, AsciiWithFacesAndComments) {
  const std::string path = scratchDir() + "/ascii.ply";
  writeBytes(path,
             "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nelement vertex 4\r\n"
             "property float x\r\nproperty float y\r\nproperty float z\r\n"
             "property uchar red\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\n"
             "end_header\r\n"
             "1 2 3 255\r\n0 0 0 0\r\n-4.5 5e2 6 1\r\n7 8 9 2\r\n3 0 1 2\r\n");
  const PointCloud cloud = readPly(path);
  ASSERT_EQ(cloud.size(), 4u);
  EXPECT_EQ(cloud.points_S[0], Eigen::Vector3f(1, 2, 3));
  EXPECT_TRUE(cloud.points_S[1].hasNaN());  // (0,0,0) = no return
  EXPECT_EQ(cloud.points_S[2], Eigen::Vector3f(-4.5f, 500.0f, 6.0f));
  EXPECT_EQ(cloud.points_S[3], Eigen::Vector3f(7, 8, 9));
}

template <typename T>
std::string bigEndian(T value) {
  std::string s = rawBytes(value);
  std::reverse(s.begin(), s.end());
  return s;
}

TEST(Ply, BinaryBigEndianDoubleAfterAnotherElement) {
  // A fixed-size element before the vertices, and a list property inside each vertex.
  std::string s =
      "ply\nformat binary_big_endian 1.0\nelement camera 2\nproperty float fov\n"
      "property ushort id\nelement vertex 3\nproperty int16 label\nproperty double z\n"
      "property list uint8 float32 extra\nproperty double x\nproperty double y\nend_header\n";
  for (int i = 0; i < 2; ++i) s += bigEndian(60.0f) + bigEndian(uint16_t(i));
  const double xyz[3][3] = {{1.25, -2.5, 3.75}, {0, 0, 0}, {1e5, 2e-3, -3.0}};
  for (int i = 0; i < 3; ++i) {
    s += bigEndian(int16_t(-i)) + bigEndian(xyz[i][2]);
    s.push_back(static_cast<char>(i));  // list of i floats
    for (int k = 0; k < i; ++k) s += bigEndian(9.0f);
    s += bigEndian(xyz[i][0]) + bigEndian(xyz[i][1]);
  }
  const std::string path = scratchDir() + "/be.ply";
  writeBytes(path, s);
  const PointCloud cloud = readPly(path);
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.points_S[0], Eigen::Vector3f(1.25f, -2.5f, 3.75f));
  EXPECT_TRUE(cloud.points_S[1].hasNaN());
  EXPECT_EQ(cloud.points_S[2], Eigen::Vector3d(1e5, 2e-3, -3.0).cast<float>());
}

TEST(Ply, CorruptedFilesAreRejectedWithTheProblem) {
  const std::string path = scratchDir() + "/bad.ply";
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  struct Case {
    std::string text;
    std::string needle;
  };
  const Case cases[] = {
      {"", "empty file"},
      {"# .PCD v0.7\nVERSION 0.7\n", "not a PLY file"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + xyz, "no end_header"},
      {"ply\nformat ascii 2.0\nelement vertex 0\n" + xyz + "end_header\n", "version 2.0"},
      {"ply\nformat utf8 1.0\nelement vertex 0\n" + xyz + "end_header\n", "unknown format"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n", "unknown type"},
      {"ply\nformat ascii 1.0\nelement vertex one\n" + xyz + "end_header\n", "element"},
      {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "before any element"},
      {"ply\nelement vertex 1\n" + xyz + "end_header\n1 2 3\n", "no format line"},
      {"ply\nformat ascii 1.0\nelement face 1\nproperty float x\nend_header\n1\n",
       "no vertex element"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n"
       "1 2\n",
       "no z property"},
      {"ply\nformat ascii 1.0\nelement vertex 2\n" + xyz + "end_header\n1 2 3\n4 5\n",
       "truncated PLY ascii data"},
      {"ply\nformat ascii 1.0\nelement vertex 1\n" + xyz + "end_header\n1 2 abc\n",
       "'abc' is not a number"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex 3\n" + xyz + "end_header\n" +
           std::string(20, '\0'),
       "truncated PLY binary data"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n" + xyz +
           "end_header\n" + std::string(20, '\0'),
       "truncated PLY binary data"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.needle);
    writeBytes(path, c.text);
    expectIoError([&] { readPly(path); }, {path, c.needle});
  }
}

// ---------------------------------------------------------------- ASCII xyz, KITTI .bin

TEST(Xyz, CommentsBlankLinesCommasAndExtraColumns) {
  const std::string path = scratchDir() + "/points.xyz";
  writeBytes(path,
             "# x y z intensity\n1 2 3 0.5\n\n  -1.5\t2.5\t3.5\r\n4,5,6,7\n   # late\n1e2 0 -0\n");
  const PointCloud cloud = readXyz(path);
  ASSERT_EQ(cloud.size(), 4u);
  EXPECT_EQ(cloud.points_S[0], Eigen::Vector3f(1, 2, 3));
  EXPECT_EQ(cloud.points_S[1], Eigen::Vector3f(-1.5f, 2.5f, 3.5f));
  EXPECT_EQ(cloud.points_S[2], Eigen::Vector3f(4, 5, 6));
  EXPECT_EQ(cloud.points_S[3], Eigen::Vector3f(100, 0, 0));

  writeBytes(path, "1 2 3\n4 5\n");
  expectIoError([&] { readXyz(path); }, {path, "line 2", "expected 'x y z'"});
  writeBytes(path, "1 2 3\n4 5 6abc\n");
  expectIoError([&] { readXyz(path); }, {path, "line 2"});
  writeBytes(path, std::string("BZh91AY&SY\0\0", 12));
  expectIoError([&] { readXyz(path); }, {path, "binary data"});
}

TEST(KittiBin, RoundTripAndBadSize) {
  const std::string dir = scratchDir();
  PointCloud cloud;
  cloud.points_S = {{1, 2, 3}, {kNan, kNan, kNan}, {-4, 5.5f, -6}};
  writeKittiBin(dir + "/000000.bin", cloud);
  EXPECT_EQ(std::filesystem::file_size(dir + "/000000.bin"), 2u * 16u);  // NaN left out
  const PointCloud back = readPointFile(dir + "/000000.bin");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back.points_S[0], Eigen::Vector3f(1, 2, 3));
  EXPECT_EQ(back.points_S[1], Eigen::Vector3f(-4, 5.5f, -6));

  writeBytes(dir + "/000001.bin", std::string(36, '\0'));
  expectIoError([&] { readKittiBin(dir + "/000001.bin"); }, {"000001.bin", "multiple of 16"});
}

// ---------------------------------------------------------------- writers

TEST(Writers, PlyAndPcdRoundTrip) {
  const std::string dir = scratchDir();
  std::vector<Eigen::Vector3f> points;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-50.0f, 50.0f);
  for (int i = 0; i < 1000; ++i) points.emplace_back(coord(rng), coord(rng), coord(rng));

  writePly(dir + "/p.ply", points);
  writePcd(dir + "/p.pcd", points);
  const PointCloud ply = readPly(dir + "/p.ply");
  const PointCloud pcd = readPcd(dir + "/p.pcd");
  ASSERT_EQ(ply.size(), points.size());
  ASSERT_EQ(pcd.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(ply.points_S[i], points[i]);
    EXPECT_EQ(pcd.points_S[i], points[i]);
  }
  EXPECT_NE(readBytes(dir + "/p.ply").find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(readBytes(dir + "/p.pcd").find("DATA binary\n"), std::string::npos);
  // Empty sets are valid files.
  writePly(dir + "/empty.ply", {});
  writePcd(dir + "/empty.pcd", std::vector<Eigen::Vector3f>{});
  EXPECT_TRUE(readPly(dir + "/empty.ply").empty());
  EXPECT_TRUE(readPcd(dir + "/empty.pcd").empty());
}

TEST(Writers, OrganisedPcdKeepsShapeAndNan) {
  const std::string dir = scratchDir();
  PointCloud cloud;
  cloud.width = 4;
  cloud.height = 3;
  for (int i = 0; i < 12; ++i)
    cloud.points_S.push_back(i % 3 == 0 ? Eigen::Vector3f::Constant(kNan)
                                        : Eigen::Vector3f(i, -i, 0.25f * i));
  writePcd(dir + "/organised.pcd", cloud);
  const PointCloud back = readPcd(dir + "/organised.pcd");
  EXPECT_EQ(back.width, 4u);
  EXPECT_EQ(back.height, 3u);
  ASSERT_EQ(back.size(), 12u);
  for (size_t i = 0; i < 12; ++i) expectSamePoint(back.points_S[i], cloud.points_S[i], i);

  PointCloud inconsistent = cloud;
  inconsistent.points_S.pop_back();
  EXPECT_THROW(writePcd(dir + "/x.pcd", inconsistent), InvalidArgument);
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.pcd"));
}

TEST(Writers, AtomicReplaceAndUnwritableFolder) {
  const std::string dir = scratchDir();
  writePly(dir + "/a.ply", {{1, 1, 1}});
  writePly(dir + "/a.ply", {{2, 2, 2}, {3, 3, 3}});
  EXPECT_EQ(readPly(dir + "/a.ply").size(), 2u);
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename(), "a.ply") << "left over: " << entry.path();
  EXPECT_THROW(writePly(dir + "/missing/a.ply", {{1, 1, 1}}), IoError);
  EXPECT_THROW(writePcd(dir + "/missing/a.pcd", {{1, 1, 1}}), IoError);
  EXPECT_FALSE(std::filesystem::exists(dir + "/missing"));
}

// ---------------------------------------------------------------- missing and damaged files

TEST(Errors, MissingFilesAndFoldersNameThePath) {
  const std::string dir = scratchDir();
  const std::string missing = dir + "/nope";
  expectIoError([&] { readPcd(missing + ".pcd"); }, {"nope.pcd", "no such file"});
  expectIoError([&] { readPly(missing + ".ply"); }, {"nope.ply", "no such file"});
  expectIoError([&] { readXyz(missing + ".xyz"); }, {"nope.xyz", "no such file"});
  expectIoError([&] { readKittiBin(missing + ".bin"); }, {"nope.bin", "no such file"});
  expectIoError([&] { readPointFile(missing + ".pcd"); }, {"nope.pcd", "no such file"});
  expectIoError([&] { readPcd(dir); }, {dir, "is a directory"});
  expectIoError([&] { readPointFile(dir + "/a.obj"); }, {"a.obj", "unknown point file extension"});
}

TEST(Errors, TruncatedRealFiles) {
  const std::string dir = scratchDir();
  struct Case {
    std::string source;
    std::string ext;
    std::string needle;
  };
  const Case cases[] = {
      {realData("nebula_single_scans/vlp16_1673400472138016708.pcd"), ".pcd", "truncated"},
      {realData("pcl_room_scans/room_scan1.pcd"), ".pcd", "truncated"},
      {realData("small_gicp_pair/source.ply"), ".ply", "truncated"},
  };
  for (const Case& c : cases) {
    const std::string bytes = readBytes(c.source);
    const std::string path = dir + "/cut" + c.ext;
    // Cut in the data, and cut inside the header.
    writeBytes(path, bytes.substr(0, bytes.size() * 6 / 10));
    expectIoError([&] { readPointFile(path); }, {path, c.needle});
    writeBytes(path, bytes.substr(0, 60));
    expectIoError([&] { readPointFile(path); }, {path});
  }
}

// Damaged copies of real and hand-made files: every prefix length class and random byte
// flips. Each must parse or throw IoError; a crash or another exception fails the test.
TEST(Errors, DamagedFilesNeverCrash) {
  const std::string dir = scratchDir();
  std::vector<std::pair<std::string, std::string>> originals;  // bytes, extension
  originals.emplace_back(readBytes(realData("nebula_single_scans/vlp16_1673400472138016708.pcd")),
                         ".pcd");
  originals.emplace_back(readBytes(realData("pcl_room_scans/room_scan2.pcd")), ".pcd");
  originals.emplace_back(readBytes(realData("small_gicp_pair/target.ply")), ".ply");
  originals.emplace_back(
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "1 2 3\n4 5 6\n7 8 9\n3 0 1 2\n",
      ".ply");
  originals.emplace_back(
      "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 2\n"
      "HEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n1 2 3 4\n5 6 7 8\nnan nan nan 0\n"
      "1 1 1 1\n",
      ".pcd");
  std::mt19937 rng(12345);
  const std::string path_base = dir + "/damaged";
  for (size_t f = 0; f < originals.size(); ++f) {
    const std::string& bytes = originals[f].first;
    const std::string path = path_base + originals[f].second;
    // Prefixes: every byte through the header, then a spread over the data.
    const size_t header_end = std::min<size_t>(bytes.size(), 400);
    std::vector<size_t> cuts;
    for (size_t cut = 0; cut < header_end; ++cut) cuts.push_back(cut);
    for (int k = 1; k < 20; ++k) cuts.push_back(bytes.size() * k / 20);
    for (size_t cut : cuts) {
      writeBytes(path, bytes.substr(0, cut));
      expectParsesOrIoError([&] { readPointFile(path); },
                            "file " + std::to_string(f) + " cut at " + std::to_string(cut));
    }
    // Random flips, mostly in the header (where they change the meaning of everything).
    for (int trial = 0; trial < 80; ++trial) {
      std::string damaged = bytes;
      const int flips = 1 + trial % 4;
      for (int k = 0; k < flips; ++k) {
        const size_t limit = trial % 3 == 0 ? damaged.size() : header_end;
        std::uniform_int_distribution<size_t> where(0, limit - 1);
        damaged[where(rng)] = static_cast<char>(rng() & 0xFF);
      }
      writeBytes(path, damaged);
      expectParsesOrIoError([&] { readPointFile(path); },
                            "file " + std::to_string(f) + " trial " + std::to_string(trial));
    }
  }
}

}  // namespace
}  // namespace fragg
