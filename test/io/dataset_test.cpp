// openDataset on every layout: single files, OctoMap ScanGraph, KITTI odometry, a folder of PCD
// files with a TUM trajectory, depth images; detection and error paths.
#include "fragg_map/io/dataset.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/io/depth_image.h"
#include "fragg_map/io/point_file.h"
#include "fragg_map/io/pose_file.h"
#include "io_test_util.h"

namespace fragg {
namespace {

namespace fs = std::filesystem;
using test::expectIoError;
using test::readBytes;
using test::realData;
using test::scratchDir;
using test::writeBytes;

std::vector<Scan> readAll(ScanSource& source) {
  std::vector<Scan> scans;
  Scan scan;
  while (source.next(scan)) scans.push_back(scan);
  EXPECT_FALSE(source.next(scan)) << "a finished source must stay finished";
  return scans;
}

Eigen::Isometry3d pose(double x, double y, double z, double roll, double pitch, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

std::string row3x4(const Eigen::Isometry3d& T) {
  std::ostringstream s;
  s << std::setprecision(17);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) s << (r || c ? " " : "") << T.matrix()(r, c);
  return s.str();
}

std::string tumLine(double stamp_s, const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  std::ostringstream s;
  s << std::setprecision(17) << stamp_s << " " << T.translation().x() << " " << T.translation().y()
    << " " << T.translation().z() << " " << q.x() << " " << q.y() << " " << q.z() << " " << q.w()
    << "\n";
  return s.str();
}

void expectPose(const Eigen::Isometry3d& actual, const Eigen::Isometry3d& expected,
                double tolerance = 1e-9) {
  EXPECT_TRUE(actual.matrix().isApprox(expected.matrix(), tolerance))
      << "actual\n"
      << actual.matrix() << "\nexpected\n"
      << expected.matrix();
}

// ---------------------------------------------------------------- single files

TEST(Dataset, SinglePointFileIsOneScanAtTheOrigin) {
  const std::string path = realData("small_gicp_pair/source.ply");
  auto source = openDataset(path);
  ASSERT_TRUE(source);
  EXPECT_EQ(source->size(), std::optional<size_t>(1));
  EXPECT_NE(source->describe().find("source.ply"), std::string::npos);
  const std::vector<Scan> scans = readAll(*source);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].cloud.size(), 69792u);
  EXPECT_EQ(scans[0].source, path);
  expectPose(scans[0].T_map_sensor, Eigen::Isometry3d::Identity());

  auto pcd = openDataset(realData("pcl_room_scans/room_scan1.pcd"));
  EXPECT_EQ(readAll(*pcd).at(0).cloud.size(), 112586u);
}

TEST(Dataset, SinglePcdViewpointBecomesThePose) {
  const std::string path = scratchDir() + "/vp.pcd";
  writeBytes(path,
             "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n"
             "HEIGHT 1\nVIEWPOINT 5 6 7 0 0 0 1\nPOINTS 1\nDATA ascii\n5 6 8\n");
  const std::vector<Scan> scans = readAll(*openDataset(path));
  ASSERT_EQ(scans.size(), 1u);
  // qw=0 qz=1: 180 degrees about z.
  Eigen::Isometry3d expected = Eigen::Isometry3d::Identity();
  expected.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  expected.translation() = Eigen::Vector3d(5, 6, 7);
  expectPose(scans[0].T_map_sensor, expected);
  // The map-frame point is the file's point.
  const Eigen::Vector3d p_map = scans[0].T_map_sensor * scans[0].cloud.points_S[0].cast<double>();
  EXPECT_TRUE(p_map.isApprox(Eigen::Vector3d(5, 6, 8), 1e-6)) << p_map.transpose();
}

// ---------------------------------------------------------------- OctoMap ScanGraph

TEST(Dataset, OctomapScanGraphSample) {
  const std::string path = realData("octomap/spherical_scan.graph");
  auto source = openDataset(path);
  EXPECT_EQ(source->size(), std::optional<size_t>(1));
  const std::vector<Scan> scans = readAll(*source);
  ASSERT_EQ(scans.size(), 1u);
  ASSERT_EQ(scans[0].cloud.size(), 10201u);
  for (const Eigen::Vector3f& p : scans[0].cloud.points_S) ASSERT_NEAR(p.norm(), 4.01, 1e-4);
  // The node pose stored in the file: translation (1, 0, -0.5), no rotation.
  Eigen::Isometry3d expected = Eigen::Isometry3d::Identity();
  expected.translation() = Eigen::Vector3d(1.0, 0.0, -0.5);
  expectPose(scans[0].T_map_sensor, expected);
}

TEST(Dataset, DamagedScanGraphsAreRejectedAtOpen) {
  const std::string dir = scratchDir();
  const std::string bytes = readBytes(realData("octomap/spherical_scan.graph"));
  const std::string path = dir + "/g.graph";
  writeBytes(path, bytes.substr(0, bytes.size() / 2));
  expectIoError([&] { openDataset(path); }, {path, "truncated ScanGraph"});
  writeBytes(path, bytes.substr(0, bytes.size() - 10));  // cut in the pose / edge count
  expectIoError([&] { openDataset(path); }, {path, "ScanGraph"});
  writeBytes(path, bytes + "junk");
  expectIoError([&] { openDataset(path); }, {path, "edges"});
  std::string bad_marker = bytes;
  bad_marker[8] = 7;  // the first point's "3"
  writeBytes(path, bad_marker);
  expectIoError([&] { openDataset(path); }, {path, "do not start with 3"});
  writeBytes(path, std::string("\xff\xff\xff\x7f", 4) + bytes.substr(4));
  expectIoError([&] { openDataset(path); }, {path, "nodes cannot fit"});
  writeBytes(path, "");
  expectIoError([&] { openDataset(path); }, {path, "node count"});
  // Any other damage: IoError or a valid parse, never a crash.
  for (size_t cut = 0; cut < 200; ++cut) {
    writeBytes(path, bytes.substr(0, cut));
    test::expectParsesOrIoError(
        [&] {
          auto s = openDataset(path);
          readAll(*s);
        },
        "cut " + std::to_string(cut));
  }
}

// ---------------------------------------------------------------- KITTI odometry

// A KITTI-layout sequence made from the two real small_gicp scans: scan 0 = target,
// scan 1 = source, with camera poses chosen so that the scans align as T_target_source says.
struct KittiFixture {
  std::string dir;
  Eigen::Isometry3d T_cam_velo;
  Eigen::Isometry3d T_map_velo[2];
  PointCloud clouds[2];
};

KittiFixture makeKitti(const std::string& root, bool official_layout) {
  KittiFixture k;
  k.dir = official_layout ? root + "/sequences/07" : root + "/seq";
  fs::create_directories(k.dir + "/velodyne");
  k.clouds[0] = readPly(realData("small_gicp_pair/target.ply"));
  k.clouds[1] = readPly(realData("small_gicp_pair/source.ply"));
  writeKittiBin(k.dir + "/velodyne/000000.bin", k.clouds[0]);
  writeKittiBin(k.dir + "/velodyne/000001.bin", k.clouds[1]);
  // KITTI's velodyne->camera rotation (x right, y down, z forward camera) plus an offset.
  k.T_cam_velo = Eigen::Isometry3d::Identity();
  k.T_cam_velo.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  k.T_cam_velo.translation() = Eigen::Vector3d(-0.004, -0.076, -0.27);
  const Eigen::Isometry3d T_target_source =
      readMatrix4(realData("small_gicp_pair/T_target_source.txt"));
  const Eigen::Isometry3d T_map_cam0 = pose(0.5, -0.2, 3.0, 0.01, -0.02, 0.3);
  // cam pose i = T_map_velo_i * T_velo_cam.
  k.T_map_velo[0] = T_map_cam0 * k.T_cam_velo;
  k.T_map_velo[1] = k.T_map_velo[0] * T_target_source;
  const Eigen::Isometry3d cam_poses[2] = {k.T_map_velo[0] * k.T_cam_velo.inverse(),
                                          k.T_map_velo[1] * k.T_cam_velo.inverse()};
  const std::string poses = row3x4(cam_poses[0]) + "\n" + row3x4(cam_poses[1]) + "\n";
  if (official_layout) {
    fs::create_directories(root + "/poses");
    writeBytes(root + "/poses/07.txt", poses);
  } else {
    writeBytes(k.dir + "/poses.txt", poses);
  }
  writeBytes(k.dir + "/calib.txt",
             "P0: 718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1 0\n"
             "Tr: " +
                 row3x4(k.T_cam_velo) + "\n");
  writeBytes(k.dir + "/times.txt", "0.000000e+00\n1.036612e-01\n");
  return k;
}

TEST(Dataset, KittiSequenceFromRealScans) {
  for (const bool official : {false, true}) {
    SCOPED_TRACE(official ? "poses in ../../poses/07.txt" : "poses.txt in the folder");
    const std::string root = scratchDir();
    const KittiFixture k = makeKitti(root, official);
    auto source = openDataset(k.dir);
    EXPECT_EQ(source->size(), std::optional<size_t>(2));
    EXPECT_NE(source->describe().find("KITTI"), std::string::npos);
    const std::vector<Scan> scans = readAll(*source);
    ASSERT_EQ(scans.size(), 2u);
    expectPose(scans[0].T_map_sensor.inverse() * scans[1].T_map_sensor,
               readMatrix4(realData("small_gicp_pair/T_target_source.txt")), 1e-6);
    for (int i = 0; i < 2; ++i) {
      size_t valid = 0;
      for (const Eigen::Vector3f& p : k.clouds[i].points_S) valid += p.allFinite();
      ASSERT_EQ(scans[i].cloud.size(), valid);
      // The reader's map frame is the Velodyne frame of KITTI's camera-0 origin (z up).
      expectPose(scans[i].T_map_sensor, k.T_cam_velo.inverse() * k.T_map_velo[i], 1e-6);
      EXPECT_NE(scans[i].source.find(i == 0 ? "000000.bin" : "000001.bin"), std::string::npos);
    }
    EXPECT_EQ(scans[0].stamp_ns, 0);
    EXPECT_EQ(scans[1].stamp_ns, 103661200);
  }
}

TEST(Dataset, KittiErrorsNameTheMissingPiece) {
  const std::string root = scratchDir();
  const KittiFixture k = makeKitti(root, false);
  fs::copy_file(k.dir + "/velodyne/000001.bin", k.dir + "/velodyne/000005.bin");
  expectIoError([&] { openDataset(k.dir); }, {"000005.bin", "no pose"});
  fs::remove(k.dir + "/velodyne/000005.bin");
  fs::copy_file(k.dir + "/velodyne/000001.bin", k.dir + "/velodyne/scan.bin");
  expectIoError([&] { openDataset(k.dir); }, {"scan.bin", "frame number"});
  fs::remove(k.dir + "/velodyne/scan.bin");
  writeBytes(k.dir + "/calib.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  expectIoError([&] { openDataset(k.dir); }, {"calib.txt", "no 'Tr:' line"});
  fs::remove(k.dir + "/calib.txt");
  expectIoError([&] { openDataset(k.dir); }, {k.dir, "calib.txt"});
  fs::remove(k.dir + "/poses.txt");
  expectIoError([&] { openDataset(k.dir); }, {k.dir, "poses.txt"});
  writeBytes(k.dir + "/poses.txt", "1 0 0 0 0 1 0 0 0 0 1\n");
  writeBytes(k.dir + "/calib.txt", "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  expectIoError([&] { openDataset(k.dir); }, {"poses.txt", "line 1", "expected 12 numbers"});
  writeBytes(k.dir + "/poses.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  expectIoError([&] { openDataset(k.dir); }, {"poses.txt", "not a rotation"});
}

// ---------------------------------------------------------------- PCD folder + TUM

TEST(Dataset, PcdFolderWithTumPosesInNameOrder) {
  const std::string dir = scratchDir();
  // Real binary_compressed scans; natural order must put scan_2 before scan_10.
  fs::copy_file(realData("pcl_room_scans/room_scan1.pcd"), dir + "/scan_2.pcd");
  fs::copy_file(realData("pcl_room_scans/room_scan2.pcd"), dir + "/scan_10.pcd");
  const Eigen::Isometry3d T0 = pose(1, 2, 0.5, 0, 0, 0.1);
  const Eigen::Isometry3d T1 = pose(1.5, 2.2, 0.5, 0, 0, 0.4);
  writeBytes(dir + "/poses.txt",
             "# timestamp tx ty tz qx qy qz qw\n" + tumLine(10.0, T0) + tumLine(10.5, T1));
  auto source = openDataset(dir);
  EXPECT_EQ(source->size(), std::optional<size_t>(2));
  const std::vector<Scan> scans = readAll(*source);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_NE(scans[0].source.find("scan_2.pcd"), std::string::npos);
  EXPECT_EQ(scans[0].cloud.size(), 112586u);
  EXPECT_EQ(scans[1].cloud.size(), 112624u);
  expectPose(scans[0].T_map_sensor, T0);
  expectPose(scans[1].T_map_sensor, T1);
  EXPECT_EQ(scans[0].stamp_ns, 10000000000);
  EXPECT_EQ(scans[1].stamp_ns, 10500000000);
}

TEST(Dataset, PcdFolderMatchedByTimeStampInTheName) {
  const std::string dir = scratchDir();
  fs::copy_file(realData("nebula_single_scans/vlp16_1673400472138016708.pcd"),
                dir + "/1305031102.195304.pcd");
  fs::copy_file(realData("nebula_single_scans/vlp32_1713492677464078412.pcd"),
                dir + "/1305031102.905000.pcd");
  std::string tum;
  for (int i = 0; i < 10; ++i)
    tum += tumLine(1305031102.0 + 0.1 * i, pose(i, 0, 0, 0, 0, 0.05 * i));
  writeBytes(dir + "/poses.txt", tum);
  const std::vector<Scan> scans = readAll(*openDataset(dir));
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[0].cloud.size(), 14831u);
  EXPECT_EQ(scans[1].cloud.size(), 26216u);
  // Closest poses: .195304 -> .2 (i = 2), .905 -> .9 (i = 9).
  expectPose(scans[0].T_map_sensor, pose(2, 0, 0, 0, 0, 0.1), 1e-6);
  expectPose(scans[1].T_map_sensor, pose(9, 0, 0, 0, 0, 0.45), 1e-6);
  EXPECT_NEAR(scans[0].stamp_ns * 1e-9, 1305031102.195304, 1e-6);

  // A scan farther than 20 ms from every pose (.195304 is 195 ms after .0).
  writeBytes(dir + "/poses.txt", tumLine(1305031102.0, pose(0, 0, 0, 0, 0, 0)) +
                                     tumLine(1305031102.9, pose(1, 0, 0, 0, 0, 0)) +
                                     tumLine(1305031103.5, pose(2, 0, 0, 0, 0, 0)));
  expectIoError([&] { openDataset(dir); }, {"1305031102.195304.pcd", "no pose within 20 ms"});
  // Counts differ and the names are not time stamps.
  fs::rename(dir + "/1305031102.195304.pcd", dir + "/a.pcd");
  expectIoError([&] { openDataset(dir); }, {dir, "2 scans but 3 poses"});
  fs::remove(dir + "/poses.txt");
  expectIoError([&] { openDataset(dir); }, {dir, "poses.txt"});
}

TEST(Dataset, TumPoseErrors) {
  const std::string path = scratchDir() + "/poses.txt";
  writeBytes(path, "1 0 0 0 0 0 0 1\n2 0 0 0 0 0\n");
  expectIoError([&] { readTumPoses(path); }, {path, "line 2", "got 6 values"});
  writeBytes(path, "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 0.5\n");
  expectIoError([&] { readTumPoses(path); }, {path, "line 2", "not a unit quaternion"});
  writeBytes(path, "1 0 0 0 0 0 0 1\n2 0 0 x 0 0 0 1\n");
  expectIoError([&] { readTumPoses(path); }, {path, "line 2", "'x' is not a finite number"});
  writeBytes(path, "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n");
  expectIoError([&] { readTumPoses(path); }, {path, "backwards"});
}

TEST(Dataset, Matrix4Files) {
  const Eigen::Isometry3d T = readMatrix4(realData("small_gicp_pair/T_target_source.txt"));
  EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-9);
  EXPECT_GT(T.translation().norm(), 0.1);  // the two scans are taken from different places
  const std::string path = scratchDir() + "/T.txt";
  writeBytes(path, "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0\n");
  expectIoError([&] { readMatrix4(path); }, {path, "16 numbers", "got 15"});
  writeBytes(path, "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n");
  expectIoError([&] { readMatrix4(path); }, {path, "0 0 0 1"});
  writeBytes(path, "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  expectIoError([&] { readMatrix4(path); }, {path, "not a rotation"});
}

// ---------------------------------------------------------------- depth images

TEST(Dataset, SlambookDepthFrames) {
  const std::string dir = realData("slambook2_ch5_rgbd");
  auto source = openDataset(dir);
  EXPECT_EQ(source->size(), std::optional<size_t>(5));
  const std::vector<Scan> scans = readAll(*source);
  ASSERT_EQ(scans.size(), 5u);
  const std::vector<StampedPose> poses = readTumPoses(dir + "/pose.txt");
  ASSERT_EQ(poses.size(), 5u);
  const DepthIntrinsics kinect;
  for (size_t i = 0; i < scans.size(); ++i) {
    const Scan& scan = scans[i];
    SCOPED_TRACE(scan.source);
    EXPECT_NE(scan.source.find("depth/" + std::to_string(i + 1) + ".pgm"), std::string::npos);
    ASSERT_TRUE(scan.cloud.organised());
    EXPECT_EQ(scan.cloud.width, 640u);
    EXPECT_EQ(scan.cloud.height, 480u);
    size_t invalid = 0;
    double min_z = INFINITY, max_z = 0;
    for (const Eigen::Vector3f& p : scan.cloud.points_S) {
      if (p.hasNaN()) {
        ++invalid;
        continue;
      }
      min_z = std::min<double>(min_z, p.z());
      max_z = std::max<double>(max_z, p.z());
    }
    const double invalid_fraction = static_cast<double>(invalid) / scan.cloud.size();
    EXPECT_GE(invalid_fraction, 0.27);
    EXPECT_LE(invalid_fraction, 0.32);
    EXPECT_GE(min_z, 0.70);
    EXPECT_LE(max_z, 9.85);  // README: "valid 0.71-9.8 m"
    expectPose(scan.T_map_sensor, poses[i].T_world_frame);
    // One pixel decoded independently: big-endian 16-bit millimetres after the header.
    const std::string bytes = readBytes(scan.source);
    const size_t data = test::offsetAfter(bytes, "65535\n");
    for (const auto& [u, v] : {std::pair<int, int>{320, 240}, {100, 400}, {600, 50}}) {
      const size_t k = static_cast<size_t>(v) * 640 + u;
      const int mm = (static_cast<unsigned char>(bytes[data + 2 * k]) << 8) |
                     static_cast<unsigned char>(bytes[data + 2 * k + 1]);
      const Eigen::Vector3f& p = scan.cloud.points_S[k];
      if (mm == 0) {
        EXPECT_TRUE(p.hasNaN());
        continue;
      }
      const double z = mm / 1000.0;
      EXPECT_NEAR(p.z(), z, 1e-6);
      EXPECT_NEAR(p.x(), (u - kinect.cx) * z / kinect.fx, 1e-5);
      EXPECT_NEAR(p.y(), (v - kinect.cy) * z / kinect.fy, 1e-5);
    }
  }
  // The first pose of pose.txt, by hand: frame 1 sits at (-0.228993, 0.00645704, 0.0287837).
  EXPECT_TRUE(scans[0].T_map_sensor.translation().isApprox(
      Eigen::Vector3d(-0.228993, 0.00645704, 0.0287837)));
}

TEST(Dataset, DepthFolderIntrinsicsOverrideAndErrors) {
  const std::string dir = scratchDir();
  fs::create_directories(dir + "/depth");
  fs::copy_file(realData("slambook2_ch5_rgbd/depth/1.pgm"), dir + "/depth/1.pgm");
  writeBytes(dir + "/pose.txt", "0 0 0 0 0 0 1\n");
  writeBytes(dir + "/intrinsics.txt", "# fx fy cx cy depth_scale\n500 400 320 240 0.002\n");
  const std::vector<Scan> scans = readAll(*openDataset(dir));
  ASSERT_EQ(scans.size(), 1u);
  const DepthImage image = readPgm(dir + "/depth/1.pgm");
  size_t checked = 0;
  for (size_t k = 0; k < image.depth.size(); k += 997) {
    if (image.depth[k] == 0) continue;
    const double z = image.depth[k] * 0.002;
    const double u = k % 640, v = k / 640;
    const Eigen::Vector3f& p = scans[0].cloud.points_S[k];
    ASSERT_NEAR(p.z(), z, 1e-5);
    ASSERT_NEAR(p.x(), (u - 320) * z / 500, 1e-5);
    ASSERT_NEAR(p.y(), (v - 240) * z / 400, 1e-5);
    ++checked;
  }
  EXPECT_GT(checked, 100u);

  writeBytes(dir + "/intrinsics.txt", "500 400 320\n");
  expectIoError([&] { openDataset(dir); }, {"intrinsics.txt", "fx fy cx cy"});
  fs::remove(dir + "/intrinsics.txt");
  writeBytes(dir + "/pose.txt", "0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n");
  expectIoError([&] { openDataset(dir); }, {dir, "1 depth images but 2 poses"});
  writeBytes(dir + "/pose.txt", "0 0 0 0 0 0 1\n");
  const std::string pgm = readBytes(dir + "/depth/1.pgm");
  writeBytes(dir + "/depth/1.pgm", pgm.substr(0, pgm.size() - 1));
  auto source = openDataset(dir);
  Scan scan;
  expectIoError([&] { source->next(scan); }, {"1.pgm", "truncated PGM data"});
  writeBytes(dir + "/depth/1.pgm", "P2\n640 480\n65535\n");
  source = openDataset(dir);
  expectIoError([&] { source->next(scan); }, {"1.pgm", "wrong magic"});
  writeBytes(dir + "/depth/1.pgm", "P5\n# comment\n640 x\n65535\n");
  source = openDataset(dir);
  expectIoError([&] { source->next(scan); }, {"1.pgm", "height"});
}

// ---------------------------------------------------------------- detection and errors

TEST(Dataset, DetectionErrors) {
  const std::string dir = scratchDir();
  expectIoError([&] { openDataset(dir + "/missing.pcd"); }, {"missing.pcd", "no such file"});
  expectIoError([&] { openDataset(""); }, {"empty dataset path"});
  expectIoError([&] { openDataset(dir); }, {dir, "not a dataset folder"});
  writeBytes(dir + "/model.obj", "v 1 2 3\n");
  expectIoError([&] { openDataset(dir + "/model.obj"); }, {"model.obj", "unknown input type"});
  expectIoError([&] { openDataset(realData("octomap/scan.dat.bz2")); },
                {"scan.dat.bz2", "decompress"});
  // A malformed single file fails when read.
  writeBytes(dir + "/bad.ply", "ply\nformat ascii 1.0\n");
  auto source = openDataset(dir + "/bad.ply");
  Scan scan;
  expectIoError([&] { source->next(scan); }, {"bad.ply", "end_header"});
}

TEST(Dataset, BagsNeedARegisteredReader) {
  const std::string dir = scratchDir();
  writeBytes(dir + "/run.bag", "#ROSBAG V2.0\n");
  registerBagOpener(nullptr);
  expectIoError([&] { openDataset(dir + "/run.bag"); }, {"run.bag", "built without ROS"});

  std::string seen_topic;
  registerBagOpener([&](const std::string& path, const DatasetOptions& options) {
    seen_topic = options.topic;
    return openDataset(realData("small_gicp_pair/target.ply"));
  });
  DatasetOptions options;
  options.topic = "/velodyne_points";
  auto source = openDataset(dir + "/run.bag", options);
  EXPECT_EQ(seen_topic, "/velodyne_points");
  EXPECT_EQ(readAll(*source).at(0).cloud.size(), 69088u);
  registerBagOpener(nullptr);
  expectIoError([&] { openDataset(dir + "/run.bag"); }, {"built without ROS"});
}

}  // namespace
}  // namespace fragg
