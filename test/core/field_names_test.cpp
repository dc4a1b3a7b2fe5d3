// Core validation messages name the core's fields; renameFields turns them into a front end's
// names (ROS parameters, CLI flags).
#include "fragg_map/field_names.h"

#include <gtest/gtest.h>

#include <string>

#include "fragg_map/map_params.h"
#include "fragg_map/sensor_model.h"

namespace fragg {
namespace {

const std::vector<FieldName> kNames = {{"occupancy.clamp_min", "sensor_model/min"},
                                       {"occupancy.clamp_max", "sensor_model/max"},
                                       {"threads", "threads"},
                                       {"sensor.min_range_m", "--min-range"},
                                       {"sensor.max_range_m", "--max-range"}};

std::string messageOf(const MapParams& p) {
  try {
    p.validate();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "(valid)";
}

TEST(FieldNames, RenamesWholeFieldsOnly) {
  EXPECT_EQ(renameFields("occupancy.clamp_min must be below occupancy.clamp_max", kNames),
            "'sensor_model/min' must be below 'sensor_model/max'");
  EXPECT_EQ(renameFields("sensor.max_range_m must exceed sensor.min_range_m.", kNames, ""),
            "--max-range must exceed --min-range.");
  // Part of a longer name: left alone.
  EXPECT_EQ(renameFields("cuda.threads and threads_per_block, threads", kNames),
            "cuda.threads and threads_per_block, 'threads'");
  EXPECT_EQ(renameFields("nothing to rename", kNames), "nothing to rename");
}

TEST(FieldNames, CoreMessagesNameTheCoreFields) {
  MapParams p;
  p.occupancy.prob_hit = 0.4;
  EXPECT_EQ(messageOf(p).rfind("occupancy.prob_hit must be > 0.5", 0), 0u) << messageOf(p);
  p = MapParams();
  p.occupancy.clamp_min = 0.99;
  EXPECT_EQ(messageOf(p), "occupancy.clamp_min must be below occupancy.clamp_max");
  p = MapParams();
  p.scans.point_step_m = 1.0;
  EXPECT_EQ(messageOf(p).rfind("scans.point_step_m ", 0), 0u) << messageOf(p);
  p = MapParams();
  p.resolution_m = 0.0;
  EXPECT_EQ(messageOf(p).rfind("resolution_m ", 0), 0u) << messageOf(p);
  SensorModel s = SensorModel::pinhole(0.0, 1.0, 0.0, 5.0);
  try {
    s.validate();
    FAIL() << "hfov 0 accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("sensor.hfov_rad ", 0), 0u) << e.what();
  }
  // No front end's names leak into the core.
  for (const char* front_end : {"sensor_model/", "--"}) {
    p = MapParams();
    p.occupancy.prob_miss = 0.7;
    EXPECT_EQ(messageOf(p).find(front_end), std::string::npos) << messageOf(p);
  }
}

TEST(FieldNames, WithFieldNamesRethrowsRenamed) {
  try {
    withFieldNames(kNames, [] { throw InvalidArgument("threads must be >= 0"); });
    FAIL() << "nothing thrown";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()), "'threads' must be >= 0");
  }
}

}  // namespace
}  // namespace fragg
