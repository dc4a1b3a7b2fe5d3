// Internal: the ScanSource implementations behind openDataset.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fragg_map/io/dataset.h"

namespace fragg {
namespace internal {

/// One scan of a file-per-scan dataset: the file and the pose of the frame its points are in.
struct ScanEntry {
  std::string path;
  Eigen::Isometry3d T_map_frame = Eigen::Isometry3d::Identity();
  int64_t stamp_ns = 0;
};

/// Reads one scan file; sets *T_frame_sensor when the file carries a sensor pose (PCD
/// VIEWPOINT), leaves it at identity otherwise.
using CloudLoader =
    std::function<PointCloud(const std::string& path, Eigen::Isometry3d* T_frame_sensor)>;

/// Scans from a list of files loaded one at a time (KITTI, PCD folder, depth folder, a single
/// point file): T_map_sensor = T_map_frame * T_frame_sensor.
class FileListSource : public ScanSource {
 public:
  FileListSource(std::vector<ScanEntry> entries, CloudLoader loader, std::string description)
      : entries_(std::move(entries)),
        loader_(std::move(loader)),
        description_(std::move(description)) {}

  bool next(Scan& scan) override;
  std::optional<size_t> size() const override { return entries_.size(); }
  std::string describe() const override { return description_; }

 private:
  std::vector<ScanEntry> entries_;
  CloudLoader loader_;
  std::string description_;
  size_t next_ = 0;
};

/// Loader for .pcd .ply .xyz .dat .txt .bin files (by extension).
PointCloud loadPointFile(const std::string& path, Eigen::Isometry3d* T_frame_sensor);

std::unique_ptr<ScanSource> openPointFileSource(const std::string& path);
std::unique_ptr<ScanSource> openScanGraph(const std::string& path);
std::unique_ptr<ScanSource> openKittiSequence(const std::string& dir);
std::unique_ptr<ScanSource> openPointFolder(const std::string& dir);
std::unique_ptr<ScanSource> openDepthFolder(const std::string& dir);

/// The first of `names` that exists as a regular file in `dir`, or "" when none does.
std::string findFileIn(const std::string& dir, const std::vector<std::string>& names);

}  // namespace internal
}  // namespace fragg
