// KITTI velodyne scans: float32 x y z intensity per point, no header.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/io/point_file.h"
#include "io_util.h"

namespace fragg {

PointCloud readKittiBin(const std::string& path) {
  // One read into the float records, then x y z copied out of each (no per-point calls).
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    internal::throwIo(path, errno == ENOENT ? std::string("no such file")
                                            : std::string("cannot open: ") + std::strerror(errno));
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    internal::throwIo(path, "is a directory or not a regular file, expected a file");
  }
  const size_t bytes = static_cast<size_t>(st.st_size);
  constexpr size_t kRecordBytes = 4 * sizeof(float);
  if (bytes % kRecordBytes != 0) {
    ::close(fd);
    internal::throwIo(path, "size " + std::to_string(bytes) +
                                " bytes is not a multiple of 16 (KITTI .bin: float32 x y z "
                                "intensity); truncated or not a KITTI scan");
  }
  const size_t n = bytes / kRecordBytes;
  std::unique_ptr<float[]> records(new float[n * 4]);  // left uninitialised: read fills it
  size_t done = 0;
  while (done < bytes) {
    const ssize_t got = ::read(fd, reinterpret_cast<char*>(records.get()) + done, bytes - done);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) {
      const std::string why = got < 0 ? std::strerror(errno) : "file shrank while reading";
      ::close(fd);
      internal::throwIo(path, "read error: " + why);
    }
    done += static_cast<size_t>(got);
  }
  ::close(fd);
  PointCloud cloud;
  cloud.points_S.resize(n);
  const float* r = records.get();
  Eigen::Vector3f* out = cloud.points_S.data();
  for (size_t i = 0; i < n; ++i, r += 4) out[i] = Eigen::Vector3f(r[0], r[1], r[2]);
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
