// HSV hue ramp over height, as octomap_server's heightMapColor (s = v = 1).
#include "fragg_map/ros/height_color.h"

#include <algorithm>
#include <cmath>

namespace fragg::ros {

std_msgs::ColorRGBA heightColor(double z_m, double min_z_m, double max_z_m, float alpha) {
  const double span = max_z_m - min_z_m;
  double t = span > 0.0 ? (z_m - min_z_m) / span : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  // Hue from 0 to 5/6 of a turn (red ... magenta) so the two ends never share a colour.
  const double h = t * 5.0;
  const int sector = std::min(static_cast<int>(std::floor(h)), 4);
  const double f = h - sector;
  double r = 0.0, g = 0.0, b = 0.0;
  switch (sector) {
    case 0:
      r = 1.0, g = f, b = 0.0;
      break;
    case 1:
      r = 1.0 - f, g = 1.0, b = 0.0;
      break;
    case 2:
      r = 0.0, g = 1.0, b = f;
      break;
    case 3:
      r = 0.0, g = 1.0 - f, b = 1.0;
      break;
    default:
      r = f, g = 0.0, b = 1.0;
      break;
  }
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(r);
  c.g = static_cast<float>(g);
  c.b = static_cast<float>(b);
  c.a = alpha;
  return c;
}

}  // namespace fragg::ros
