#include "fragg_map/internal/scan_codec.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/map_file_format.h"

namespace fragg {

namespace {
constexpr int16_t kNoReturn = std::numeric_limits<int16_t>::min();
constexpr double kMaxQuantised = 32767.0;
/// Farther points do not widen a scan's step; they are moved along their ray instead.
constexpr double kStepRangeCap_m = 1000.0;
constexpr char kSpillMagic[8] = {'F', 'R', 'A', 'G', 'G', 'S', 'C', 'N'};

double maxAbsCoordinate(const Eigen::Vector3f& p) {
  return static_cast<double>(p.cwiseAbs().maxCoeff());
}
}  // namespace

EncodedPoints encodePoints(const PointCloud& cloud, double step_m, PointCloud* decoded) {
  EncodedPoints out;
  out.width = cloud.width;
  out.height = cloud.height;
  out.count = cloud.size();
  if (decoded) {
    decoded->width = cloud.width;
    decoded->height = cloud.height;
  }
  const long n = static_cast<long>(cloud.size());
  if (step_m <= 0.0) {
    out.step_m = 0.0;
    out.data.resize(out.dataBytes());
    if (out.count) std::memcpy(out.data.data(), cloud.points_S.data(), out.data.size());
    if (decoded) decoded->points_S = cloud.points_S;
    return out;
  }
  double far = 0.0;
#pragma omp parallel for schedule(static) reduction(max : far) if (n > 20000)
  for (long i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = cloud.points_S[i];
    if (p.allFinite()) far = std::max(far, std::min(maxAbsCoordinate(p), kStepRangeCap_m));
  }
  out.step_m = std::max(step_m, far / kMaxQuantised);
  out.data.resize(out.dataBytes());
  if (decoded) decoded->points_S.resize(cloud.size());
  auto* q_all = reinterpret_cast<int16_t*>(out.data.data());
  const double limit = kMaxQuantised * out.step_m;
  const float nan = std::numeric_limits<float>::quiet_NaN();
#pragma omp parallel for schedule(static) if (n > 20000)
  for (long i = 0; i < n; ++i) {
    int16_t* q = q_all + 3 * i;
    const Eigen::Vector3f& p = cloud.points_S[i];
    if (!p.allFinite()) {
      q[0] = q[1] = q[2] = kNoReturn;
      if (decoded) decoded->points_S[i] = Eigen::Vector3f::Constant(nan);
      continue;
    }
    const double m = maxAbsCoordinate(p);
    const double scale = m > limit ? limit / m : 1.0;
    for (int a = 0; a < 3; ++a) {
      const double v = std::round(static_cast<double>(p[a]) * scale / out.step_m);
      q[a] = static_cast<int16_t>(std::clamp(v, -kMaxQuantised, kMaxQuantised));
      if (decoded)
        decoded->points_S[i][a] = static_cast<float>(static_cast<double>(q[a]) * out.step_m);
    }
  }
  return out;
}

PointCloud decodePoints(const EncodedPoints& points) {
  PointCloud cloud;
  decodePoints(points, &cloud);
  return cloud;
}

void decodePoints(const EncodedPoints& points, PointCloud* out) {
  PointCloud& cloud = *out;
  cloud.width = points.width;
  cloud.height = points.height;
  cloud.free_only.clear();
  cloud.points_S.resize(points.count);
  if (points.step_m <= 0.0) {
    if (points.count)
      std::memcpy(static_cast<void*>(cloud.points_S.data()), points.data.data(),
                  points.dataBytes());
    return;
  }
  const auto* q_all = reinterpret_cast<const int16_t*>(points.data.data());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const long n = static_cast<long>(points.count);
#pragma omp parallel for schedule(static) if (n > 20000)
  for (long i = 0; i < n; ++i) {
    const int16_t* q = q_all + 3 * i;
    if (q[0] == kNoReturn) {
      cloud.points_S[i] = Eigen::Vector3f::Constant(nan);
      continue;
    }
    for (int a = 0; a < 3; ++a)
      cloud.points_S[i][a] = static_cast<float>(static_cast<double>(q[a]) * points.step_m);
  }
}

void writeScan(ByteWriter& w, const ScanRecord& r, const EncodedPoints& p) {
  w.put(r.id);
  w.put(r.stamp_ns);
  const Eigen::Matrix<double, 3, 4> T = r.T_map_sensor.matrix().topRows<3>();
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 3; ++row) w.put(T(row, c));  // exact bits: removal repeats the rays
  const SensorModel& m = r.model;
  w.put(static_cast<uint8_t>(m.type));
  w.put(static_cast<uint8_t>(m.optical_axis));
  w.put(static_cast<uint8_t>(r.explicit_model));
  w.put(static_cast<uint8_t>(r.raycast));
  // Ray flags: bit 0 no-return rays cleared, bit 1 the cut cell freed (a reader before the cut
  // cell rule refuses bit 1 rather than walk the scan differently).
  w.put(static_cast<uint8_t>(uint8_t(r.clear_no_return_rays) | uint8_t(r.free_cut_cell) << 1));
  w.put(static_cast<uint8_t>(r.removable));
  for (double v : {m.hfov_rad, m.vfov_rad, m.elevation_min_rad, m.elevation_max_rad, m.min_range_m,
                   m.max_range_m})
    w.put(v);
  for (int a = 0; a < 3; ++a) w.put(m.forward_S[a]);
  for (int a = 0; a < 3; ++a) w.put(m.right_S[a]);
  w.put(m.range_noise_m);
  w.put(m.range_noise_quadratic_per_m);
  w.put(static_cast<uint16_t>(r.sensor_frame.size()));
  w.put(r.sensor_frame.data(), r.sensor_frame.size());
  w.put(p.step_m);
  w.put(p.width);
  w.put(p.height);
  w.put(p.count);
  if (p.data.size() != p.dataBytes()) throw IoError("scan " + std::to_string(r.id) + ": no points");
  std::vector<uint8_t> packed(compressBound(p.data.size()));
  uLongf packed_size = packed.size();
  if (compress2(packed.data(), &packed_size, p.data.data(), p.data.size(), 1) != Z_OK)
    throw IoError("scan " + std::to_string(r.id) + ": compression failed");
  w.put(static_cast<uint64_t>(packed_size));
  w.put(packed.data(), packed_size);
}

void readScan(ByteReader& rd, ScanRecord& r, EncodedPoints& p, uint32_t file_version) {
  r.id = rd.get<ScanId>("scan id");
  r.stamp_ns = rd.get<int64_t>("scan stamp");
  Eigen::Matrix<double, 3, 4> T;
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 3; ++row) T(row, c) = rd.get<double>("scan pose");
  if (!T.allFinite()) rd.fail("scan " + std::to_string(r.id) + ": pose is not finite");
  r.T_map_sensor.matrix().topRows<3>() = T;
  r.T_map_sensor.matrix().row(3) << 0, 0, 0, 1;
  SensorModel& m = r.model;
  const auto type = rd.get<uint8_t>("sensor type");
  const auto axis = rd.get<uint8_t>("optical axis");
  const auto explicit_model = rd.get<uint8_t>("explicit model flag");
  const auto raycast = rd.get<uint8_t>("ray cast mode");
  const auto no_return = rd.get<uint8_t>("no-return flag");
  const auto removable = rd.get<uint8_t>("removable flag");
  if (type != uint8_t(SensorType::kSpinningLidar) && type != uint8_t(SensorType::kPinhole))
    rd.fail("scan " + std::to_string(r.id) + ": unknown sensor type " + std::to_string(type));
  if (axis > uint8_t(OpticalAxis::kXForward) || explicit_model > 1 ||
      raycast > uint8_t(RayCast::kOctomap) || no_return > 3 || removable > 1)
    rd.fail("scan " + std::to_string(r.id) + ": bad sensor or insertion flags");
  m.type = static_cast<SensorType>(type);
  m.optical_axis = static_cast<OpticalAxis>(axis);
  r.explicit_model = explicit_model != 0;
  r.raycast = static_cast<RayCast>(raycast);
  r.clear_no_return_rays = (no_return & 1) != 0;
  r.free_cut_cell = (no_return & 2) != 0;
  r.removable = removable != 0;
  for (double* v : {&m.hfov_rad, &m.vfov_rad, &m.elevation_min_rad, &m.elevation_max_rad,
                    &m.min_range_m, &m.max_range_m})
    *v = rd.get<double>("sensor model");
  for (int a = 0; a < 3; ++a) m.forward_S[a] = rd.get<double>("sensor axis");
  for (int a = 0; a < 3; ++a) m.right_S[a] = rd.get<double>("sensor axis");
  m.range_noise_m = 0.0;
  m.range_noise_quadratic_per_m = 0.0;
  r.sensor_frame.clear();
  if (file_version >= 3) {
    m.range_noise_m = rd.get<double>("range noise");
    m.range_noise_quadratic_per_m = rd.get<double>("range noise");
    const auto frame_chars = rd.get<uint16_t>("sensor frame length");
    if (frame_chars > kMaxSensorFrameChars)
      rd.fail("scan " + std::to_string(r.id) + ": sensor frame id too long");
    r.sensor_frame.resize(frame_chars);
    rd.take(r.sensor_frame.data(), frame_chars, "sensor frame");
  }
  try {
    m.validate();
  } catch (const InvalidArgument& e) {
    rd.fail("scan " + std::to_string(r.id) + ": bad sensor model: " + e.what());
  }
  p.step_m = rd.get<double>("point step");
  p.width = rd.get<uint32_t>("cloud width");
  p.height = rd.get<uint32_t>("cloud height");
  p.count = rd.get<uint64_t>("point count");
  if (!std::isfinite(p.step_m) || p.step_m < 0.0 || p.step_m > 1.0)
    rd.fail("scan " + std::to_string(r.id) + ": bad point step");
  if (p.count == 0 || p.count > (uint64_t{1} << 32))
    rd.fail("scan " + std::to_string(r.id) + ": bad point count");
  r.points = p.count;
  const auto packed_size = rd.get<uint64_t>("packed points size");
  if (packed_size > rd.remaining()) rd.fail("truncated scan points");
  if (p.dataBytes() > packed_size * 1100 + 64)  // zlib cannot pack more densely than ~1:1032
    rd.fail("scan " + std::to_string(r.id) + ": point count larger than its data");
  std::vector<uint8_t> packed(packed_size);
  rd.take(packed.data(), packed.size(), "scan points");
  p.data.resize(p.dataBytes());
  uLongf out_size = p.data.size();
  if (uncompress(p.data.data(), &out_size, packed.data(), packed.size()) != Z_OK ||
      out_size != p.data.size())
    rd.fail("scan " + std::to_string(r.id) + ": points do not decompress to " +
            std::to_string(p.data.size()) + " bytes");
}

void writeSpillFile(const std::string& path, const ScanRecord& record,
                    const EncodedPoints& points) {
  ByteWriter w;
  w.put(kSpillMagic, sizeof(kSpillMagic));
  writeScan(w, record, points);
  const auto crc = static_cast<uint32_t>(crc32(0L, w.bytes.data(), w.bytes.size()));
  w.put(crc);
  AtomicFile file(path);
  file.write(w.bytes.data(), w.bytes.size());
  file.commit();
}

EncodedPoints readSpillFile(const std::string& path, ScanId expected_id) {
  const std::vector<uint8_t> bytes = readWholeFile(path);
  ByteReader r(bytes, bytes.size() >= 4 ? bytes.size() - 4 : 0, path, "not a valid spilled scan");
  if (bytes.size() < sizeof(kSpillMagic) + 4) r.fail("file too short");
  uint32_t stored_crc;
  std::memcpy(&stored_crc, bytes.data() + bytes.size() - 4, 4);
  if (static_cast<uint32_t>(crc32(0L, bytes.data(), bytes.size() - 4)) != stored_crc)
    r.fail("checksum mismatch (file corrupted or truncated)");
  char magic[8];
  r.take(magic, sizeof(magic), "magic");
  if (std::memcmp(magic, kSpillMagic, sizeof(magic)) != 0) r.fail("wrong magic");
  ScanRecord record;
  EncodedPoints points;
  readScan(r, record, points, kMapFileVersion);  // spill files are this build's own
  if (record.id != expected_id)
    r.fail("holds scan " + std::to_string(record.id) + ", not " + std::to_string(expected_id));
  return points;
}

}  // namespace fragg
