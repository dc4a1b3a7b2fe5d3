// Pose files, each reader on the same bytes: TUM (dataset folders), `fragg_map correct --poses`,
// KITTI poses.txt, calib.txt (Tr), a 4x4 matrix and KITTI times.txt.
#include "fragg_map/errors.h"
#include "fragg_map/io/pose_file.h"
#include "fuzz_targets.h"
#include "fuzz_util.h"

namespace fragg::fuzz {
namespace {

// True when `read` returns, false when it refuses the file with a project error.
template <class Read>
bool readCatching(Read read) {
  try {
    read();
    return true;
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
  return false;
}

}  // namespace

// Parsed when at least one of the pose readers reads the file (every reader is run).
bool poses(const uint8_t* data, size_t size) {
  const std::string path = writeInputFile(data, size, ".txt");
  bool parsed = false;
  parsed |= readCatching([&] { readTumPoses(path); });
  parsed |= readCatching([&] { readScanPoses(path); });
  parsed |= readCatching([&] { readKittiPoses(path); });
  parsed |= readCatching([&] { readKittiCalibTr(path); });
  parsed |= readCatching([&] { readMatrix4(path); });
  parsed |= readCatching([&] { readKittiTimes(path); });
  return parsed;
}

}  // namespace fragg::fuzz
