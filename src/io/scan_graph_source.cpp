// OctoMap ScanGraph binary files (octomap::ScanGraph::writeBinary), parsed without liboctomap.
//
//   uint32 node_count
//   node_count x { Pointcloud: uint32 n, n x (int32 3, double x y z)
//                  pose6d:     int32 3, double x y z, int32 4, double qw qx qy qz
//                  uint32 id }
//   uint32 edge_count
//   edge_count x { uint32 first_id, uint32 second_id, pose6d constraint, double weight }
//
// All little-endian. Node points are in the sensor frame; the pose is T_map_sensor.
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "io_util.h"
#include "scan_sources.h"

namespace fragg {
namespace internal {
namespace {

constexpr uint64_t kPointBytes = 4 + 3 * 8;
constexpr uint64_t kPoseBytes = (4 + 3 * 8) + (4 + 4 * 8);
constexpr uint64_t kEdgeBytes = 4 + 4 + kPoseBytes + 8;

struct GraphNode {
  uint64_t points_offset = 0;  // first point record
  uint32_t point_count = 0;
  uint32_t id = 0;
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
};

// Reads exactly `bytes` at `offset`; throws (naming `what`) when the file is shorter.
void readAt(std::ifstream& in, const std::string& path, uint64_t offset, char* out, uint64_t bytes,
            const std::string& what) {
  in.clear();
  in.seekg(static_cast<std::streamoff>(offset));
  in.read(out, static_cast<std::streamsize>(bytes));
  if (static_cast<uint64_t>(in.gcount()) != bytes)
    throwIo(path, "truncated ScanGraph: " + what + " at byte " + std::to_string(offset));
}

Eigen::Isometry3d parsePose(const std::string& path, const char* bytes, const std::string& what) {
  ByteCursor cursor(bytes, kPoseBytes, path);
  if (cursor.read<int32_t>("pose") != 3)
    throwIo(path, "corrupted ScanGraph: " + what + " translation does not start with 3");
  double t[3], q[4];
  for (double& v : t) v = cursor.read<double>("pose");
  if (cursor.read<int32_t>("pose") != 4)
    throwIo(path, "corrupted ScanGraph: " + what + " rotation does not start with 4");
  for (double& v : q) v = cursor.read<double>("pose");
  for (double v : t)
    if (!std::isfinite(v)) throwIo(path, "corrupted ScanGraph: " + what + " is not finite");
  const Eigen::Quaterniond rotation = checkedQuaternion(q[1], q[2], q[3], q[0], path + ": " + what);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotation.toRotationMatrix();
  T.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
  return T;
}

class ScanGraphSource : public ScanSource {
 public:
  explicit ScanGraphSource(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!isRegularFile(path)) throwIo(path, isDirectory(path) ? "is a directory" : "no such file");
    if (!in_) throwIo(path, "cannot open");
    in_.seekg(0, std::ios::end);
    const uint64_t file_size = static_cast<uint64_t>(in_.tellg());
    index(file_size);
  }

  bool next(Scan& scan) override {
    if (next_ >= nodes_.size()) return false;
    const GraphNode& node = nodes_[next_++];
    std::vector<char> bytes(node.point_count * kPointBytes);
    readAt(in_, path_, node.points_offset, bytes.data(), bytes.size(), "points");
    scan.cloud = PointCloud();
    scan.cloud.points_S.resize(node.point_count);
    ByteCursor cursor(bytes.data(), bytes.size(), path_);
    for (uint32_t i = 0; i < node.point_count; ++i) {
      if (cursor.read<int32_t>("point") != 3)
        throwIo(path_, "corrupted ScanGraph: node " + std::to_string(node.id) + " point " +
                           std::to_string(i) + " does not start with 3");
      for (int axis = 0; axis < 3; ++axis)
        scan.cloud.points_S[i][axis] = static_cast<float>(cursor.read<double>("point"));
    }
    scan.T_map_sensor = node.T_map_sensor;
    scan.stamp_ns = 0;
    scan.source = path_ + " node " + std::to_string(node.id);
    return true;
  }

  std::optional<size_t> size() const override { return nodes_.size(); }
  std::string describe() const override {
    return "OctoMap ScanGraph " + path_ + " (" + std::to_string(nodes_.size()) + " scans, " +
           std::to_string(edge_count_) + " edges)";
  }

 private:
  // One pass over the structure (seeking past the points) so that truncated or corrupted
  // files fail at open, before any scan is used.
  void index(uint64_t file_size) {
    uint32_t node_count = 0;
    readAt(in_, path_, 0, reinterpret_cast<char*>(&node_count), 4, "node count");
    uint64_t offset = 4;
    // Each node takes at least 4 + pose + 4 bytes: a garbage count fails here.
    if (node_count > (file_size - offset) / (4 + kPoseBytes + 4))
      throwIo(path_, "not a ScanGraph file or truncated: " + std::to_string(node_count) +
                         " nodes cannot fit in " + std::to_string(file_size) + " bytes");
    nodes_.reserve(node_count);
    for (uint32_t i = 0; i < node_count; ++i) {
      GraphNode node;
      readAt(in_, path_, offset, reinterpret_cast<char*>(&node.point_count), 4,
             "point count of node " + std::to_string(i));
      offset += 4;
      node.points_offset = offset;
      const uint64_t points_bytes = uint64_t{node.point_count} * kPointBytes;
      if (points_bytes > file_size - offset)
        throwIo(path_, "truncated ScanGraph: node " + std::to_string(i) + " claims " +
                           std::to_string(node.point_count) + " points, the file ends " +
                           std::to_string(file_size - offset) + " bytes later");
      offset += points_bytes;
      // The first point's marker catches a misaligned or non-ScanGraph file early.
      if (node.point_count > 0) {
        int32_t marker = 0;
        readAt(in_, path_, node.points_offset, reinterpret_cast<char*>(&marker), 4, "point");
        if (marker != 3)
          throwIo(path_, "not a ScanGraph file or corrupted: node " + std::to_string(i) +
                             " points do not start with 3");
      }
      char pose[kPoseBytes];
      readAt(in_, path_, offset, pose, kPoseBytes, "pose of node " + std::to_string(i));
      node.T_map_sensor = parsePose(path_, pose, "pose of node " + std::to_string(i));
      offset += kPoseBytes;
      readAt(in_, path_, offset, reinterpret_cast<char*>(&node.id), 4,
             "id of node " + std::to_string(i));
      offset += 4;
      nodes_.push_back(node);
    }
    uint32_t edge_count = 0;
    readAt(in_, path_, offset, reinterpret_cast<char*>(&edge_count), 4, "edge count");
    offset += 4;
    if (uint64_t{edge_count} * kEdgeBytes != file_size - offset)
      throwIo(path_, "corrupted ScanGraph: " + std::to_string(edge_count) + " edges need " +
                         std::to_string(uint64_t{edge_count} * kEdgeBytes) + " bytes, " +
                         std::to_string(file_size - offset) + " follow the nodes");
    edge_count_ = edge_count;
  }

  std::string path_;
  std::ifstream in_;
  std::vector<GraphNode> nodes_;
  uint32_t edge_count_ = 0;
  size_t next_ = 0;
};

}  // namespace

std::unique_ptr<ScanSource> openScanGraph(const std::string& path) {
  return std::make_unique<ScanGraphSource>(path);
}

}  // namespace internal
}  // namespace fragg
