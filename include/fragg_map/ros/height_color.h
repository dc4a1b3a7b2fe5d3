// Height -> colour ramp for markers (octomap_server's HSV ramp: one full hue turn).
#pragma once

#include <std_msgs/ColorRGBA.h>

namespace fragg::ros {

/// Colour of height `z_m` on a hue ramp from `min_z_m` to `max_z_m` (clamped at the ends).
std_msgs::ColorRGBA heightColor(double z_m, double min_z_m, double max_z_m, float alpha);

}  // namespace fragg::ros
