// .fgm maps: Map::load as `fragg_map` and the server's ~load_map call it (the file's kept scans
// loaded too), then every kept scan decoded as a pose correction would.
#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/scan_store.h"
#include "fuzz_targets.h"
#include "fuzz_util.h"

namespace fragg::fuzz {

bool fgm(const uint8_t* data, size_t size) {
  const std::string path = writeInputFile(data, size, ".fgm", /*append_crc=*/true);
  try {
    const Map map = Map::load(path, Backend::kCpu);
    for (const ScanId id : map.scanStore().ids()) decodePoints(map.scanStore().points(id));
    return true;
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
  return false;
}

}  // namespace fragg::fuzz
