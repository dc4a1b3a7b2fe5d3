// .pcd point files: readPcd as the dataset readers and `fragg_map build` call it.
#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "fuzz_targets.h"
#include "fuzz_util.h"

namespace fragg::fuzz {

bool pcd(const uint8_t* data, size_t size) {
  const std::string path = writeInputFile(data, size, ".pcd");
  try {
    Eigen::Isometry3d T_file_sensor;
    readPcd(path, &T_file_sensor);
    return true;
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
  return false;
}

}  // namespace fragg::fuzz
