// Kept-scan records: byte 0 picks the format version (2, 3 or 4, as in the .fgm's scan
// section) and, with bit 7 set, a spill file of the scan store ("FRAGGSCN" | record | CRC-32,
// the CRC appended here) instead of a record in memory. The points are decoded as the map does
// before re-inserting a scan.
#include <cstring>

#include "fragg_map/errors.h"
#include "fragg_map/internal/byte_io.h"
#include "fragg_map/internal/scan_codec.h"
#include "fuzz_targets.h"
#include "fuzz_util.h"

namespace fragg::fuzz {

bool scan(const uint8_t* data, size_t size) {
  if (size < 1) return false;
  const uint32_t version = 2 + data[0] % 3;
  const bool spill_file = (data[0] & 0x80) != 0;
  try {
    if (spill_file) {
      const std::string path = writeInputFile(data + 1, size - 1, ".fgs", /*append_crc=*/true);
      // The id a spill file should hold comes from the store; 0 is as good as any.
      decodePoints(readSpillFile(path, 0));
    } else {
      const std::vector<uint8_t> bytes(data + 1, data + size);
      ByteReader reader(bytes, bytes.size(), "<fuzz input>", "scan record");
      ScanRecord record;
      EncodedPoints points;
      readScan(reader, record, points, version);
      decodePoints(points);
    }
    return true;
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
  return false;
}

}  // namespace fragg::fuzz
