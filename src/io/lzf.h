// LZF decompression (the format of liblzf, used by PCD's binary_compressed).
#pragma once

#include <cstddef>

namespace fragg {
namespace internal {

/// Decompresses `in` into exactly `out_size` bytes at `out`. Returns false when the stream is
/// malformed: a back reference before the start of the output, a run past the end of the input
/// or the output, or an output shorter than `out_size`.
bool lzfDecompress(const unsigned char* in, size_t in_size, unsigned char* out, size_t out_size);

}  // namespace internal
}  // namespace fragg
