// KITTI velodyne scans: float32 x y z intensity per point, no header.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "io_util.h"

namespace fragg {

PointCloud readKittiBin(const std::string& path) {
  const std::string bytes = internal::readFileBytes(path);
  constexpr size_t kRecordBytes = 4 * sizeof(float);
  if (bytes.size() % kRecordBytes != 0)
    internal::throwIo(path, "size " + std::to_string(bytes.size()) +
                                " bytes is not a multiple of 16 (KITTI .bin: float32 x y z "
                                "intensity); truncated or not a KITTI scan");
  PointCloud cloud;
  const size_t n = bytes.size() / kRecordBytes;
  cloud.points_S.resize(n);
  for (size_t i = 0; i < n; ++i) {
    float record[4];
    std::memcpy(record, bytes.data() + i * kRecordBytes, kRecordBytes);
    cloud.points_S[i] = Eigen::Vector3f(record[0], record[1], record[2]);
  }
  return cloud;
}

void writeKittiBin(const std::string& path, const PointCloud& cloud) {
  std::vector<float> records;
  records.reserve(cloud.size() * 4);
  for (const Eigen::Vector3f& p : cloud.points_S) {
    if (!p.allFinite()) continue;
    records.insert(records.end(), {p.x(), p.y(), p.z(), 0.0f});
  }
  AtomicFile file(path);
  file.write(records.data(), records.size() * sizeof(float));
  file.commit();
}

}  // namespace fragg
