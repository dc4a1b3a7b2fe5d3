// .xyz point files: readXyz as the dataset readers and `fragg_map build` call it.
#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "fuzz_targets.h"
#include "fuzz_util.h"

namespace fragg::fuzz {

bool xyz(const uint8_t* data, size_t size) {
  const std::string path = writeInputFile(data, size, ".xyz");
  try {
    readXyz(path);
    return true;
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
  return false;
}

}  // namespace fragg::fuzz
