// Helpers of the fuzz targets: the input as a temporary file for readers that take a path.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace fragg::fuzz {

/// Writes `size` bytes (and, with `append_crc`, their CRC-32 as the 4-byte little-endian
/// footer of the .fgm and spill files) to a file of this process in the temporary folder,
/// named <stem><extension>, and returns its path. The file is overwritten by the next call with
/// the same stem and extension, and removed when the process exits.
std::string writeInputFile(const uint8_t* data, size_t size, const std::string& extension,
                           bool append_crc = false);

}  // namespace fragg::fuzz
