// libFuzzer's entry point for one target: FRAGG_FUZZ_ENTRY names its function (fuzz.cmake).
#include <cstddef>
#include <cstdint>

#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return fragg::fuzz::FRAGG_FUZZ_ENTRY(data, size);
}
