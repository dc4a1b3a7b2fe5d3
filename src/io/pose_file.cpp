// TUM and KITTI pose lists.
#include "fragg_map/io/pose_file.h"

#include <cmath>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "io_util.h"

namespace fragg {
namespace {

using internal::TextLine;
using internal::throwIo;

std::vector<double> parseNumbers(const std::string& path, const TextLine& line,
                                 const std::vector<std::string>& tokens) {
  std::vector<double> values(tokens.size());
  for (size_t i = 0; i < tokens.size(); ++i) {
    if (!internal::parseDouble(tokens[i], &values[i]) || !std::isfinite(values[i]))
      throwIo(path, "line " + std::to_string(line.number) + ": '" + tokens[i] +
                        "' is not a finite number");
  }
  return values;
}

// Rows of a 3x4 row-major matrix as an isometry; rejects a rotation that is not orthonormal.
Eigen::Isometry3d isometryFrom3x4(const std::string& path, size_t line_number, const double* m) {
  Eigen::Matrix3d R;
  R << m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10];
  const double error = (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (error > 1e-3 || R.determinant() < 0.0)
    throwIo(path, "line " + std::to_string(line_number) +
                      ": the 3x3 part is not a rotation (orthonormality error " +
                      std::to_string(error) + ")");
  // Re-orthonormalise (files print 6-9 digits) so that products of poses stay rigid.
  const Eigen::Quaterniond q(R);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(m[3], m[7], m[11]);
  return T;
}

}  // namespace

std::vector<StampedPose> readTumPoses(const std::string& path) {
  std::vector<StampedPose> poses;
  for (const TextLine& line : internal::readDataLines(path)) {
    const std::vector<std::string> tokens = internal::splitTokens(line.text, true);
    if (tokens.size() != 8 && tokens.size() != 7)
      throwIo(path, "line " + std::to_string(line.number) + ": expected 'timestamp tx ty tz qx " +
                        "qy qz qw' (8 numbers) or 'tx ty tz qx qy qz qw' (7), got " +
                        std::to_string(tokens.size()) + " values");
    const std::vector<double> v = parseNumbers(path, line, tokens);
    const size_t o = tokens.size() == 8 ? 1 : 0;
    StampedPose pose;
    pose.stamp_s = o ? v[0] : 0.0;
    const Eigen::Quaterniond q = internal::checkedQuaternion(
        v[o + 3], v[o + 4], v[o + 5], v[o + 6], path + ": line " + std::to_string(line.number));
    pose.T_world_frame.linear() = q.toRotationMatrix();
    pose.T_world_frame.translation() = Eigen::Vector3d(v[o], v[o + 1], v[o + 2]);
    if (!poses.empty() && tokens.size() == 8 && pose.stamp_s < poses.back().stamp_s)
      throwIo(path, "line " + std::to_string(line.number) + ": time stamps go backwards");
    poses.push_back(pose);
  }
  return poses;
}

std::map<uint64_t, Eigen::Isometry3d> readScanPoses(const std::string& path) {
  std::map<uint64_t, Eigen::Isometry3d> poses;
  for (const TextLine& line : internal::readDataLines(path)) {
    const std::string where = "line " + std::to_string(line.number);
    const std::vector<std::string> tokens = internal::splitTokens(line.text, true);
    if (tokens.size() != 8)
      throwIo(path, where + ": expected 'scan_index tx ty tz qx qy qz qw', got " +
                        std::to_string(tokens.size()) + " values");
    uint64_t index = 0;
    if (!internal::parseUint64(tokens[0], &index))
      throwIo(path, where + ": '" + tokens[0] + "' is not a scan index (0, 1, 2, ...)");
    const std::vector<double> v =
        parseNumbers(path, line, std::vector<std::string>(tokens.begin() + 1, tokens.end()));
    const Eigen::Quaterniond q =
        internal::checkedQuaternion(v[3], v[4], v[5], v[6], path + ": " + where);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.toRotationMatrix();
    T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    if (!poses.emplace(index, T).second)
      throwIo(path, where + ": scan " + std::to_string(index) + " is listed twice");
  }
  if (poses.empty()) throwIo(path, "no poses (expected 'scan_index tx ty tz qx qy qz qw' lines)");
  return poses;
}

std::vector<Eigen::Isometry3d> readKittiPoses(const std::string& path) {
  std::vector<Eigen::Isometry3d> poses;
  for (const TextLine& line : internal::readDataLines(path)) {
    const std::vector<std::string> tokens = internal::splitTokens(line.text);
    if (tokens.size() != 12)
      throwIo(path, "line " + std::to_string(line.number) +
                        ": expected 12 numbers (3x4 row-major pose), got " +
                        std::to_string(tokens.size()));
    const std::vector<double> v = parseNumbers(path, line, tokens);
    poses.push_back(isometryFrom3x4(path, line.number, v.data()));
  }
  return poses;
}

Eigen::Isometry3d readKittiCalibTr(const std::string& path) {
  for (const TextLine& line : internal::readDataLines(path)) {
    std::vector<std::string> tokens = internal::splitTokens(line.text);
    if (tokens.empty() || (tokens[0] != "Tr:" && tokens[0] != "Tr_velo_to_cam:")) continue;
    tokens.erase(tokens.begin());
    if (tokens.size() != 12)
      throwIo(path, "line " + std::to_string(line.number) + ": Tr needs 12 numbers, got " +
                        std::to_string(tokens.size()));
    const std::vector<double> v = parseNumbers(path, line, tokens);
    return isometryFrom3x4(path, line.number, v.data());
  }
  throwIo(path, "no 'Tr:' line (velodyne to camera transform) in the KITTI calibration");
}

Eigen::Isometry3d readMatrix4(const std::string& path) {
  std::vector<double> v;
  int last_line = 0;
  for (const TextLine& line : internal::readDataLines(path)) {
    const std::vector<std::string> tokens = internal::splitTokens(line.text, /*commas=*/true);
    const std::vector<double> row = parseNumbers(path, line, tokens);
    v.insert(v.end(), row.begin(), row.end());
    last_line = line.number;
  }
  if (v.size() != 16)
    throwIo(path, "expected a 4x4 matrix (16 numbers), got " + std::to_string(v.size()));
  if (v[12] != 0.0 || v[13] != 0.0 || v[14] != 0.0 || v[15] != 1.0)
    throwIo(path, "the last row of a rigid transform must be 0 0 0 1");
  return isometryFrom3x4(path, last_line, v.data());
}

std::vector<double> readKittiTimes(const std::string& path) {
  std::vector<double> times;
  for (const TextLine& line : internal::readDataLines(path)) {
    const std::vector<std::string> tokens = internal::splitTokens(line.text);
    if (tokens.size() != 1)
      throwIo(path, "line " + std::to_string(line.number) + ": expected one time in seconds");
    times.push_back(parseNumbers(path, line, tokens)[0]);
  }
  return times;
}

}  // namespace fragg
