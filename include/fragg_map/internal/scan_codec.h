// Scan records in binary form: inside the .fgm map (its scan section) and in the spill files
// of the scan store. Points are zlib-compressed; every field is checked on reading.
#pragma once

#include <string>

#include "fragg_map/internal/byte_io.h"
#include "fragg_map/scan_store.h"

namespace fragg {

/// Writes the current format (the .fgm's kMapFileVersion).
void writeScan(ByteWriter& w, const ScanRecord& record, const EncodedPoints& points);
/// Reads a scan written by .fgm version `file_version` (2: no range noise and no frame id,
/// read as 0 and empty). Throws
/// IoError (through the reader) naming the bad field.
void readScan(ByteReader& r, ScanRecord& record, EncodedPoints& points, uint32_t file_version);

/// A spill file: "FRAGGSCN" | scan | CRC-32. Written atomically.
void writeSpillFile(const std::string& path, const ScanRecord& record, const EncodedPoints& points);
EncodedPoints readSpillFile(const std::string& path, ScanId expected_id);

}  // namespace fragg
