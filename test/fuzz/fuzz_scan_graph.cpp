// OctoMap ScanGraph files (.graph): openDataset, then every scan read as `fragg_map build` does.
#include "fragg_map/errors.h"
#include "fragg_map/io/dataset.h"
#include "fuzz_targets.h"
#include "fuzz_util.h"

namespace fragg::fuzz {

bool scanGraph(const uint8_t* data, size_t size) {
  const std::string path = writeInputFile(data, size, ".graph");
  try {
    const auto source = openDataset(path);
    Scan scan;
    while (source->next(scan)) {
    }
    return true;
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
  return false;
}

}  // namespace fragg::fuzz
