// libFuzzer's entry point for one target: FRAGG_FUZZ_ENTRY names its function (tests.cmake).
// Whether the input parsed does not matter to libFuzzer: it always gets 0 (a non-zero value is
// reserved by libFuzzer).
#include <cstddef>
#include <cstdint>

#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static_cast<void>(fragg::fuzz::FRAGG_FUZZ_ENTRY(data, size));
  return 0;
}
