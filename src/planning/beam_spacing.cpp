#include "fragg_map/planning/beam_spacing.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace fragg::planning {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kWedgeRad = 1.0 * kDeg;      // azimuth wedge
constexpr int32_t kWedges = 361;              // 2 pi / kWedgeRad, and 2 pi itself
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
  // It runs on the insertion thread for the first clouds: the samples' trigonometry on the
  // map's threads (one slot per sample, then compacted in order), their elevations sorted
  // within each azimuth wedge (a counting sort by wedge, each wedge's few hundred sorted in
  // parallel), every buffer sized once. The steps are those of one sort by (wedge, elevation).
  const int64_t n = static_cast<int64_t>((points_S.size() + stride - 1) / stride);
  std::vector<int32_t> wedges(static_cast<size_t>(n));
  std::vector<double> elevations(static_cast<size_t>(n)), ranges(static_cast<size_t>(n));
#pragma omp parallel for schedule(static) if (n > 8192)
  for (int64_t j = 0; j < n; ++j) {
    const Eigen::Vector3d p = points_S[static_cast<size_t>(j) * stride].cast<double>();
    const double horizontal = std::hypot(p.x(), p.y()), range = p.norm();
    if (!p.allFinite() || range < 1.0 || horizontal <= 0.0) {
      wedges[j] = -1;
      continue;
    }
    const double azimuth = std::atan2(p.y(), p.x()) + M_PI;  // [0, 2 pi]
    wedges[j] = std::min(int32_t(azimuth / kWedgeRad), kWedges - 1);
    elevations[j] = std::atan2(p.z(), horizontal);
    ranges[j] = range;
  }
  size_t kept = 0;
  for (int64_t j = 0; j < n; ++j) {
    if (wedges[j] < 0) continue;
    wedges[kept] = wedges[j];
    elevations[kept] = elevations[j];
    ranges[kept] = ranges[j];
    ++kept;
  }
  wedges.resize(kept);
  elevations.resize(kept);
  ranges.resize(kept);
  if (kept < kMinPoints) return std::nullopt;
  std::vector<size_t> first(kWedges + 1, 0);
  for (const int32_t w : wedges) ++first[static_cast<size_t>(w) + 1];
  for (size_t w = 1; w <= kWedges; ++w) first[w] += first[w - 1];
  std::vector<double> by_wedge(kept);
  {
    std::vector<size_t> next(first.begin(), first.end() - 1);
    for (size_t i = 0; i < kept; ++i)
      by_wedge[next[static_cast<size_t>(wedges[i])]++] = elevations[i];
  }
#pragma omp parallel for schedule(dynamic, 16) if (kept > 8192)
  for (int32_t w = 0; w < kWedges; ++w)
    std::sort(by_wedge.begin() + ptrdiff_t(first[w]), by_wedge.begin() + ptrdiff_t(first[w + 1]));
  std::vector<double> steps;
  steps.reserve(kept);
  for (size_t w = 0; w < static_cast<size_t>(kWedges); ++w) {
    for (size_t i = first[w] + 1; i < first[w + 1]; ++i) {
      const double step = by_wedge[i] - by_wedge[i - 1];
      if (step >= kSameBeamRad) steps.push_back(step);
    }
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
