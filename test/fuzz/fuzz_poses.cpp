// Pose files, each reader on the same bytes: TUM (dataset folders), `fragg_map correct --poses`,
// KITTI poses.txt, calib.txt (Tr), a 4x4 matrix and KITTI times.txt.
#include "fragg_map/errors.h"
#include "fragg_map/io/pose_file.h"
#include "fuzz_targets.h"
#include "fuzz_util.h"

namespace fragg::fuzz {
namespace {

template <class Read>
void readCatching(Read read) {
  try {
    read();
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
}

}  // namespace

int poses(const uint8_t* data, size_t size) {
  const std::string path = writeInputFile(data, size, ".txt");
  readCatching([&] { readTumPoses(path); });
  readCatching([&] { readScanPoses(path); });
  readCatching([&] { readKittiPoses(path); });
  readCatching([&] { readKittiCalibTr(path); });
  readCatching([&] { readMatrix4(path); });
  readCatching([&] { readKittiTimes(path); });
  return 0;
}

}  // namespace fragg::fuzz
