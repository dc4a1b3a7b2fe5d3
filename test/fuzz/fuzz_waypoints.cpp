// `fragg_map collide --waypoints` files.
#include "fragg_map/errors.h"
#include "fragg_map/planning/waypoint_file.h"
#include "fuzz_targets.h"
#include "fuzz_util.h"

namespace fragg::fuzz {

bool waypoints(const uint8_t* data, size_t size) {
  const std::string path = writeInputFile(data, size, ".txt");
  try {
    planning::readWaypoints(path);
    return true;
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
  return false;
}

}  // namespace fragg::fuzz
