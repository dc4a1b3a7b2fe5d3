// Shared by the gpu tests: REQUIRE_DEVICE() skips the calling gtest (with the reason) where no
// CUDA device is usable, so the gpu suites also run on machines without one; kSlotBytes sizes
// a small device block pool in slots.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <string>

#include "fragg_map/internal/backend_factory.h"

#define REQUIRE_DEVICE()                                    \
  do {                                                      \
    std::string why_no_device;                              \
    if (::fragg::cudaDeviceName(0, &why_no_device).empty()) \
      GTEST_SKIP() << "skipped: " << why_no_device;         \
  } while (0)

namespace fragg::test {
/// Sizes the small pools of the gpu tests: SlotPool::bytesPerSlot() is 2,368 bytes (2 KiB of
/// cells, the state masks, key, scratch marks, stamps, culling memory), so `n * kSlotBytes` as
/// CudaParams::pool_max_bytes gives about 1.03 n slots: the pools the tests were tuned with
/// (`n * 2300` bytes at 2,232 bytes a slot before the masks).
constexpr size_t kSlotBytes = 2440;
}  // namespace fragg::test
