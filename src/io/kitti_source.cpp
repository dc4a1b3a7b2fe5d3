// KITTI odometry sequence folder: velodyne/NNNNNN.bin, poses.txt (camera-0 poses, 3x4
// row-major per line; also found as ../../poses/<sequence>.txt in the official layout),
// calib.txt (Tr: velodyne -> camera), optional times.txt. The map frame is the first scan's
// Velodyne frame (z up, as robots and renderers expect; KITTI's camera frame has y down):
// T_map_sensor = Tr^-1 * pose[i] * Tr.
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "fragg_map/io/pose_file.h"
#include "io_util.h"
#include "scan_sources.h"

namespace fragg {
namespace internal {

std::unique_ptr<ScanSource> openKittiSequence(const std::string& dir) {
  namespace fs = std::filesystem;
  const std::vector<std::string> scans = listFiles(dir + "/velodyne", {".bin"});
  if (scans.empty()) throwIo(dir, "KITTI sequence without scans (velodyne/*.bin)");

  std::string poses_path = findFileIn(dir, {"poses.txt"});
  if (poses_path.empty()) {
    const fs::path sequence = fs::path(dir).lexically_normal();
    const std::string name = sequence.has_filename() ? sequence.filename().string()
                                                     : sequence.parent_path().filename().string();
    const fs::path official = sequence.parent_path().parent_path() / "poses" / (name + ".txt");
    if (isRegularFile(official.string())) poses_path = official.string();
  }
  if (poses_path.empty())
    throwIo(dir, "KITTI sequence without poses.txt (nor ../../poses/<sequence>.txt)");
  const std::string calib_path = findFileIn(dir, {"calib.txt"});
  if (calib_path.empty()) throwIo(dir, "KITTI sequence without calib.txt (Tr: velodyne->camera)");

  const std::vector<Eigen::Isometry3d> poses = readKittiPoses(poses_path);
  const Eigen::Isometry3d T_cam_velo = readKittiCalibTr(calib_path);
  std::vector<double> times;
  const std::string times_path = findFileIn(dir, {"times.txt"});
  if (!times_path.empty()) times = readKittiTimes(times_path);

  std::vector<ScanEntry> entries;
  entries.reserve(scans.size());
  for (const std::string& scan : scans) {
    // Scan files are named by their frame index, which is their line in poses.txt.
    uint64_t index = 0;
    if (!parseUint64(fileStem(scan), &index))
      throwIo(scan, "KITTI scan name is not a frame number (expected e.g. 000042.bin)");
    if (index >= poses.size())
      throwIo(scan, "frame " + std::to_string(index) + " has no pose: " + poses_path + " has " +
                        std::to_string(poses.size()) + " lines");
    ScanEntry entry;
    entry.path = scan;
    entry.T_map_frame = T_cam_velo.inverse() * poses[index] * T_cam_velo;
    if (!times.empty()) {
      if (index >= times.size())
        throwIo(scan, "frame " + std::to_string(index) + " has no time in " + times_path);
      entry.stamp_ns = static_cast<int64_t>(std::llround(times[index] * 1e9));
    }
    entries.push_back(entry);
  }
  const std::string description =
      "KITTI odometry sequence " + dir + " (" + std::to_string(entries.size()) + " scans)";
  return std::make_unique<FileListSource>(
      std::move(entries),
      [](const std::string& path, Eigen::Isometry3d*) { return readKittiBin(path); }, description);
}

}  // namespace internal
}  // namespace fragg
