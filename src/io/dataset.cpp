// openDataset: recognises the input and opens the matching reader.
#include "fragg_map/io/dataset.h"

#include <filesystem>
#include <mutex>
#include <string>
#include <utility>

#include "fragg_map/errors.h"
#include "io_util.h"
#include "scan_sources.h"

namespace fragg {
namespace {

std::mutex& openerMutex() {
  static std::mutex mutex;
  return mutex;
}

DatasetOpener& bagOpener() {
  static DatasetOpener opener;
  return opener;
}

}  // namespace

void registerBagOpener(DatasetOpener opener) {
  std::lock_guard<std::mutex> lock(openerMutex());
  bagOpener() = std::move(opener);
}

std::unique_ptr<ScanSource> openDataset(const std::string& input, const DatasetOptions& options) {
  namespace fs = std::filesystem;
  using internal::isDirectory;
  using internal::throwIo;
  if (input.empty()) throw IoError("empty dataset path");
  std::error_code ec;
  if (!fs::exists(input, ec)) throwIo(input, "no such file or folder");

  if (isDirectory(input)) {
    if (isDirectory(input + "/velodyne")) return internal::openKittiSequence(input);
    if (isDirectory(input + "/depth")) return internal::openDepthFolder(input);
    if (!internal::listFiles(input, {".pcd", ".ply"}).empty())
      return internal::openPointFolder(input);
    throwIo(input,
            "not a dataset folder: expected velodyne/ + poses.txt + calib.txt (KITTI), "
            "depth/*.pgm + pose.txt (depth images), or *.pcd + poses.txt (TUM trajectory)");
  }

  const std::string ext = internal::lowerExtension(input);
  if (ext == ".bag") {
    DatasetOpener opener;
    {
      std::lock_guard<std::mutex> lock(openerMutex());
      opener = bagOpener();
    }
    if (!opener)
      throwIo(input,
              "cannot read ROS bags: fragg_map was built without ROS (or the bag reader "
              "was not registered)");
    return opener(input, options);
  }
  if (ext == ".graph") return internal::openScanGraph(input);
  return internal::openPointFileSource(input);
}

}  // namespace fragg
