// A folder of PCD (or PLY) scans with a TUM trajectory (poses.txt or pose.txt,
// "timestamp tx ty tz qx qy qz qw"). Scans and poses pair up in natural file-name order when
// their counts agree; otherwise each scan named by its time stamp ("1305031102.175304.pcd",
// seconds, or nanoseconds when the number is that large) takes the pose closest in time,
// at most 20 ms away.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/io/pose_file.h"
#include "io_util.h"
#include "scan_sources.h"

namespace fragg {
namespace internal {
namespace {

constexpr double kMaxStampGapS = 0.02;

int64_t toNs(double stamp_s) { return static_cast<int64_t>(std::llround(stamp_s * 1e9)); }

// Seconds from a file name, or false when the name is not a time stamp.
bool stampFromName(const std::string& path, double* stamp_s) {
  double value = 0.0;
  if (!parseDouble(fileStem(path), &value) || !std::isfinite(value) || value < 0) return false;
  *stamp_s = value > 1e14 ? value * 1e-9 : value;  // nanoseconds since the epoch
  return true;
}

}  // namespace

std::unique_ptr<ScanSource> openPointFolder(const std::string& dir) {
  const std::vector<std::string> scans = listFiles(dir, {".pcd", ".ply"});
  if (scans.empty()) throwIo(dir, "no .pcd or .ply scans in the folder");
  const std::string poses_path = findFileIn(dir, {"poses.txt", "pose.txt"});
  if (poses_path.empty())
    throwIo(dir, "folder of scans without poses.txt (TUM: timestamp tx ty tz qx qy qz qw)");
  const std::vector<StampedPose> poses = readTumPoses(poses_path);

  std::vector<ScanEntry> entries;
  if (poses.size() == scans.size()) {
    for (size_t i = 0; i < scans.size(); ++i)
      entries.push_back({scans[i], poses[i].T_world_frame, toNs(poses[i].stamp_s)});
  } else {
    for (const std::string& scan : scans) {
      double stamp_s = 0.0;
      if (!stampFromName(scan, &stamp_s))
        throwIo(dir, std::to_string(scans.size()) + " scans but " + std::to_string(poses.size()) +
                         " poses in " + poses_path +
                         ": give one pose per scan, or name the scans by their time stamp "
                         "(e.g. 1305031102.175304.pcd) to match them by time");
      const auto later =
          std::lower_bound(poses.begin(), poses.end(), stamp_s,
                           [](const StampedPose& pose, double t) { return pose.stamp_s < t; });
      const StampedPose* best = nullptr;
      if (later != poses.end()) best = &*later;
      if (later != poses.begin()) {
        const StampedPose* earlier = &*(later - 1);
        if (!best || stamp_s - earlier->stamp_s < best->stamp_s - stamp_s) best = earlier;
      }
      const double gap_s = best ? std::abs(best->stamp_s - stamp_s) : INFINITY;
      if (gap_s > kMaxStampGapS)
        throwIo(scan, "no pose within 20 ms of the scan's time stamp in " + poses_path +
                          " (closest: " + std::to_string(gap_s) + " s away)");
      entries.push_back({scan, best->T_world_frame, toNs(stamp_s)});
    }
  }
  const std::string description = "folder of scans " + dir + " with poses " + poses_path + " (" +
                                  std::to_string(entries.size()) + " scans)";
  return std::make_unique<FileListSource>(std::move(entries), loadPointFile, description);
}

}  // namespace internal
}  // namespace fragg
