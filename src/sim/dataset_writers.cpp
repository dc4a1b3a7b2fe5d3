#include "fragg_map/sim/dataset_writers.h"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "fragg_map/sim/depth_camera.h"

namespace fragg::sim {
namespace {

void makeDir(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(dir + ": cannot create folder: " + ec.message());
}

void writeText(const std::string& path, const std::string& text) {
  AtomicFile f(path);
  f.write(text);
  f.commit();
}

std::string frameName(size_t i, const char* ext) { return fmt::format("{:06d}{}", i, ext); }

// labels/NNNNNN.dyn of the points kept[i] != 0.
void writeLabels(const std::string& dir, size_t index, const std::vector<uint8_t>& labels,
                 const std::vector<char>& kept) {
  std::string bytes;
  for (size_t i = 0; i < labels.size(); ++i)
    if (kept[i]) bytes.push_back(static_cast<char>(labels[i] ? 1 : 0));
  writeText(dir + "/labels/" + frameName(index, ".dyn"), bytes);
}

void checkLabelCount(const PointCloud& cloud, const std::vector<uint8_t>* labels) {
  if (labels && labels->size() != cloud.size())
    throw InvalidArgument("dataset writer: " + std::to_string(labels->size()) + " labels for " +
                          std::to_string(cloud.size()) + " points");
}

}  // namespace

std::vector<uint8_t> readDynamicLabels(const std::string& dir, size_t index) {
  const std::string path = dir + "/labels/" + frameName(index, ".dyn");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open labels file");
  std::vector<uint8_t> labels((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
  for (uint8_t v : labels)
    if (v > 1) throw IoError(path + ": a label is " + std::to_string(v) + " (0 or 1 expected)");
  return labels;
}

std::string tumPoseLines(const std::vector<Eigen::Isometry3d>& poses,
                         const std::vector<double>& stamps_s) {
  std::string out;
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Vector3d t = poses[i].translation();
    const Eigen::Quaterniond q(poses[i].linear());
    out += fmt::format("{:.6f} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g}\n", stamps_s[i],
                       t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  }
  return out;
}

std::string kittiPoseLines(const std::vector<Eigen::Isometry3d>& poses) {
  std::string out;
  for (const Eigen::Isometry3d& T : poses) {
    const Eigen::Matrix4d& m = T.matrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        out += fmt::format("{:.9g}{}", m(r, c), r == 2 && c == 3 ? "\n" : " ");
  }
  return out;
}

void writePgm16(const std::string& path, const DepthImage& image) {
  AtomicFile f(path);
  f.write(fmt::format("P5\n{} {}\n65535\n", image.width, image.height));
  std::string data(image.depth.size() * 2, '\0');
  for (size_t i = 0; i < image.depth.size(); ++i) {
    data[2 * i] = static_cast<char>(image.depth[i] >> 8);
    data[2 * i + 1] = static_cast<char>(image.depth[i] & 0xff);
  }
  f.write(data);
  f.commit();
}

KittiFolderWriter::KittiFolderWriter(const std::string& dir, bool organised)
    : dir_(dir), organised_(organised) {
  makeDir(dir_ + "/velodyne");
  if (organised_) makeDir(dir_ + "/organised");
}

void KittiFolderWriter::add(const PointCloud& cloud_S, const Eigen::Isometry3d& T_map_sensor,
                            const Eigen::Isometry3d& T_odom_sensor, double stamp_s,
                            const std::vector<uint8_t>* dynamic_labels) {
  checkLabelCount(cloud_S, dynamic_labels);
  const size_t i = gt_.size();
  if (dynamic_labels) {
    makeDir(dir_ + "/labels");
    std::vector<char> kept(cloud_S.size());
    for (size_t k = 0; k < cloud_S.size(); ++k) kept[k] = cloud_S.points_S[k].allFinite();
    writeLabels(dir_, i, *dynamic_labels, kept);
  }
  writeKittiBin(dir_ + "/velodyne/" + frameName(i, ".bin"), cloud_S);
  if (organised_) writePcd(dir_ + "/organised/" + frameName(i, ".pcd"), cloud_S);
  gt_.push_back(T_map_sensor);
  odom_.push_back(T_odom_sensor);
  stamps_.push_back(stamp_s);
}

void KittiFolderWriter::finish() {
  writeText(dir_ + "/poses.txt", kittiPoseLines(gt_));
  writeText(dir_ + "/poses_odom.txt", kittiPoseLines(odom_));
  std::string times;
  for (double t : stamps_) times += fmt::format("{:.6f}\n", t);
  writeText(dir_ + "/times.txt", times);
  writeText(dir_ + "/calib.txt",
            "# fragg_map_sim: the poses are the LiDAR's own (Tr = identity)\n"
            "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  if (organised_) writeText(dir_ + "/organised/poses.txt", tumPoseLines(gt_, stamps_));
}

DepthFolderWriter::DepthFolderWriter(const std::string& dir, const DepthIntrinsics& intrinsics)
    : dir_(dir), intrinsics_(intrinsics) {
  makeDir(dir_ + "/depth");
}

void DepthFolderWriter::add(const PointCloud& cloud_C, const Eigen::Isometry3d& T_map_camera,
                            const Eigen::Isometry3d& T_odom_camera, double stamp_s,
                            const std::vector<uint8_t>* dynamic_labels) {
  checkLabelCount(cloud_C, dynamic_labels);
  const DepthImage image = toDepthImage(cloud_C, intrinsics_.depth_scale_m);
  writePgm16(dir_ + "/depth/" + frameName(gt_.size(), ".pgm"), image);
  if (dynamic_labels) {  // the pixels the reader gives back: non-zero depth
    makeDir(dir_ + "/labels");
    std::vector<char> kept(image.depth.size());
    for (size_t k = 0; k < image.depth.size(); ++k) kept[k] = image.depth[k] != 0;
    writeLabels(dir_, gt_.size(), *dynamic_labels, kept);
  }
  gt_.push_back(T_map_camera);
  odom_.push_back(T_odom_camera);
  stamps_.push_back(stamp_s);
}

void DepthFolderWriter::finish() {
  writeText(dir_ + "/pose.txt", tumPoseLines(gt_, stamps_));
  writeText(dir_ + "/pose_odom.txt", tumPoseLines(odom_, stamps_));
  writeText(dir_ + "/intrinsics.txt",
            fmt::format("# fx fy cx cy depth_scale_m\n{:.9g} {:.9g} {:.9g} {:.9g} {:.9g}\n",
                        intrinsics_.fx, intrinsics_.fy, intrinsics_.cx, intrinsics_.cy,
                        intrinsics_.depth_scale_m));
}

}  // namespace fragg::sim
