#include "fragg_map/planning/beam_spacing.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace fragg::planning {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kWedgeRad = 1.0 * kDeg;      // azimuth wedge
constexpr double kSameBeamRad = 0.02 * kDeg;  // closer elevations: one beam
constexpr size_t kMaxSamples = 60000;
constexpr size_t kMinPoints = 1000;
constexpr size_t kMinSteps = 200;

double median(std::vector<double> v) {
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + ptrdiff_t(mid), v.end());
  return v[mid];
}

}  // namespace

std::optional<BeamSpacing> estimateBeamSpacing(const std::vector<Eigen::Vector3f>& points_S) {
  const size_t stride = std::max<size_t>(1, points_S.size() / kMaxSamples);
  struct Sample {
    int32_t wedge;
    double elevation_rad;
  };
  std::vector<Sample> samples;
  std::vector<double> ranges;
  for (size_t i = 0; i < points_S.size(); i += stride) {
    const Eigen::Vector3d p = points_S[i].cast<double>();
    if (!p.allFinite()) continue;
    const double horizontal = std::hypot(p.x(), p.y()), range = p.norm();
    if (range < 1.0 || horizontal <= 0.0) continue;
    const double azimuth = std::atan2(p.y(), p.x()) + M_PI;  // [0, 2 pi]
    samples.push_back({int32_t(azimuth / kWedgeRad), std::atan2(p.z(), horizontal)});
    ranges.push_back(range);
  }
  if (samples.size() < kMinPoints) return std::nullopt;
  std::sort(samples.begin(), samples.end(), [](const Sample& a, const Sample& b) {
    return a.wedge != b.wedge ? a.wedge < b.wedge : a.elevation_rad < b.elevation_rad;
  });
  std::vector<double> steps;
  for (size_t i = 1; i < samples.size(); ++i) {
    if (samples[i].wedge != samples[i - 1].wedge) continue;
    const double step = samples[i].elevation_rad - samples[i - 1].elevation_rad;
    if (step >= kSameBeamRad) steps.push_back(step);
  }
  if (steps.size() < kMinSteps) return std::nullopt;
  BeamSpacing b;
  b.angle_rad = median(std::move(steps));
  if (b.angle_rad < 0.03 * kDeg || b.angle_rad > 10.0 * kDeg) return std::nullopt;
  const size_t far = std::min(ranges.size() - 1, size_t(0.99 * double(ranges.size())));
  std::nth_element(ranges.begin(), ranges.begin() + ptrdiff_t(far), ranges.end());
  b.range_m = ranges[far];
  return b;
}

void BeamSpacingTracker::add(const BeamSpacing& b) {
  if (!wantsMore()) return;
  angles_.push_back(b.angle_rad);
  ranges_.push_back(b.range_m);
}

std::optional<BeamSpacing> BeamSpacingTracker::estimate() const {
  if (angles_.empty()) return std::nullopt;
  return BeamSpacing{median(angles_), median(ranges_)};
}

}  // namespace fragg::planning
