// FileListSource and the single-point-file dataset.
#include <string>
#include <utility>

#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "io_util.h"
#include "scan_sources.h"

namespace fragg {
namespace internal {

bool FileListSource::next(Scan& scan) {
  if (next_ >= entries_.size()) return false;
  const ScanEntry& entry = entries_[next_++];
  Eigen::Isometry3d T_frame_sensor = Eigen::Isometry3d::Identity();
  scan.cloud = loader_(entry.path, &T_frame_sensor);
  scan.T_map_sensor = entry.T_map_frame * T_frame_sensor;
  scan.stamp_ns = entry.stamp_ns;
  scan.source = entry.path;
  return true;
}

PointCloud loadPointFile(const std::string& path, Eigen::Isometry3d* T_frame_sensor) {
  if (lowerExtension(path) == ".pcd") return readPcd(path, T_frame_sensor);
  return readPointFile(path);
}

std::unique_ptr<ScanSource> openPointFileSource(const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (ext == ".bz2" || ext == ".gz" || ext == ".xz" || ext == ".zip")
    throwIo(path, "compressed file; decompress it first (e.g. bunzip2 -k)");
  if (ext != ".pcd" && ext != ".ply" && ext != ".xyz" && ext != ".dat" && ext != ".txt" &&
      ext != ".bin")
    throwIo(path, "unknown input type '" + ext +
                      "': expected a .bag, a .graph, a point file (.pcd .ply .xyz .dat .txt "
                      ".bin) or a dataset folder");
  if (!isRegularFile(path)) throwIo(path, "not a regular file");
  std::vector<ScanEntry> entries(1);
  entries[0].path = path;
  return std::make_unique<FileListSource>(std::move(entries), loadPointFile,
                                          "point file " + path + " (1 scan)");
}

std::string findFileIn(const std::string& dir, const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    const std::string path = dir + "/" + name;
    if (isRegularFile(path)) return path;
  }
  return {};
}

}  // namespace internal
}  // namespace fragg
