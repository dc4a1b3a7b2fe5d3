#include "lzf.h"

#include <cstring>

namespace fragg {
namespace internal {

// An LZF stream is a sequence of chunks, each introduced by a control byte:
//   000LLLLL                      literal run: the next L+1 bytes are copied as they are
//   LLLooooo [LLLLLLLL] oooooooo  back reference: copy len+2 bytes from `offset+1` bytes back
//                                 in the output, len = LLL (or 7 + the extra byte when LLL = 7),
//                                 offset = the 13 bits ooooo oooooooo
bool lzfDecompress(const unsigned char* in, size_t in_size, unsigned char* out, size_t out_size) {
  const unsigned char* ip = in;
  const unsigned char* const in_end = in + in_size;
  unsigned char* op = out;
  unsigned char* const out_end = out + out_size;

  while (ip < in_end) {
    size_t ctrl = *ip++;
    if (ctrl < (1u << 5)) {
      const size_t run = ctrl + 1;
      if (run > static_cast<size_t>(in_end - ip) || run > static_cast<size_t>(out_end - op))
        return false;
      std::memcpy(op, ip, run);
      op += run;
      ip += run;
    } else {
      size_t len = ctrl >> 5;
      size_t back = (ctrl & 0x1f) << 8;
      if (len == 7) {
        if (ip >= in_end) return false;
        len += *ip++;
      }
      if (ip >= in_end) return false;
      back += *ip++;
      len += 2;
      if (back + 1 > static_cast<size_t>(op - out)) return false;
      if (len > static_cast<size_t>(out_end - op)) return false;
      const unsigned char* ref = op - back - 1;
      // Byte by byte: the source may overlap the bytes being written (run-length style).
      for (size_t i = 0; i < len; ++i) *op++ = *ref++;
    }
  }
  return op == out_end;
}

}  // namespace internal
}  // namespace fragg
