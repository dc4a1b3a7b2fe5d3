// Front ends (ROS parameters, CLI flags) name the core's fields their own way. The core's
// validate() functions are the only place values are checked; their InvalidArgument messages
// name fields by their C++ path ("occupancy.prob_hit must be > 0.5"), and a front end renames
// them for its user ("'sensor_model/hit' must be > 0.5") with a table of its names.
#pragma once

#include <string>
#include <vector>

#include "fragg_map/errors.h"

namespace fragg {

/// One core field ("occupancy.prob_hit", "sensor.max_range_m") and a front end's name for it.
struct FieldName {
  std::string field;
  std::string name;
};

/// `message` with every whole-word occurrence of a table field replaced by
/// `quote + name + quote` (a field inside a longer dotted or underscored name is left alone).
std::string renameFields(const std::string& message, const std::vector<FieldName>& names,
                         const std::string& quote = "'");

/// Runs `fn`; an InvalidArgument it throws is thrown again with its fields renamed.
template <typename Fn>
void withFieldNames(const std::vector<FieldName>& names, Fn&& fn, const std::string& quote = "'") {
  try {
    fn();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(renameFields(e.what(), names, quote));
  }
}

}  // namespace fragg
