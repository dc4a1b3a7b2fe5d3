// A folder of depth images: depth/*.pgm (16-bit millimetres), pose.txt with one camera pose
// per image in natural file-name order ("tx ty tz qx qy qz qw", or TUM with a time stamp),
// optional intrinsics.txt ("fx fy cx cy [depth_scale_m]"; Kinect v1 defaults otherwise).
// Clouds are organised, in the camera optical frame, NaN where the depth is 0.
#include <cmath>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/io/depth_image.h"
#include "fragg_map/io/pose_file.h"
#include "io_util.h"
#include "scan_sources.h"

namespace fragg {
namespace internal {

std::unique_ptr<ScanSource> openDepthFolder(const std::string& dir) {
  const std::vector<std::string> images = listFiles(dir + "/depth", {".pgm"});
  if (images.empty()) throwIo(dir, "depth folder without depth/*.pgm images");
  const std::string poses_path = findFileIn(dir, {"pose.txt", "poses.txt"});
  if (poses_path.empty())
    throwIo(dir, "depth folder without pose.txt (one 'tx ty tz qx qy qz qw' line per image)");
  const std::vector<StampedPose> poses = readTumPoses(poses_path);
  if (poses.size() != images.size())
    throwIo(dir, std::to_string(images.size()) + " depth images but " +
                     std::to_string(poses.size()) + " poses in " + poses_path);
  DepthIntrinsics intrinsics;
  const std::string intrinsics_path = findFileIn(dir, {"intrinsics.txt"});
  if (!intrinsics_path.empty()) intrinsics = readDepthIntrinsics(intrinsics_path);

  std::vector<ScanEntry> entries;
  for (size_t i = 0; i < images.size(); ++i) {
    entries.push_back({images[i], poses[i].T_world_frame,
                       static_cast<int64_t>(std::llround(poses[i].stamp_s * 1e9))});
  }
  const std::string description = "depth images " + dir + " (" + std::to_string(images.size()) +
                                  " frames, fx " + std::to_string(intrinsics.fx) + " fy " +
                                  std::to_string(intrinsics.fy) + ")";
  return std::make_unique<FileListSource>(
      std::move(entries),
      [intrinsics](const std::string& path, Eigen::Isometry3d*) {
        return depthToCloud(readPgm(path), intrinsics);
      },
      description);
}

}  // namespace internal
}  // namespace fragg
