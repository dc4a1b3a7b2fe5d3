// The map and the lock every thread takes to use it (insertion worker, publishers, services).
#pragma once

#include <mutex>
#include <utility>

#include "fragg_map/map.h"

namespace fragg_ros {

struct SharedMap {
  explicit SharedMap(fragg::Map m) : map(std::move(m)) {}
  std::mutex mutex;
  fragg::Map map;
};

}  // namespace fragg_ros
