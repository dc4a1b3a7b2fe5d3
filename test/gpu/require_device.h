// REQUIRE_DEVICE(): skips the calling gtest (with the reason) where no CUDA device is usable, so
// the gpu suites also run on machines without one.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "fragg_map/internal/backend_factory.h"

#define REQUIRE_DEVICE()                                    \
  do {                                                      \
    std::string why_no_device;                              \
    if (::fragg::cudaDeviceName(0, &why_no_device).empty()) \
      GTEST_SKIP() << "skipped: " << why_no_device;         \
  } while (0)
