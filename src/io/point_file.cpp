// readPointFile: picks the reader from the file extension.
#include "fragg_map/io/point_file.h"

#include <string>

#include "fragg_map/errors.h"
#include "io_util.h"

namespace fragg {

PointCloud readPointFile(const std::string& path) {
  const std::string ext = internal::lowerExtension(path);
  if (ext == ".pcd") return readPcd(path);
  if (ext == ".ply") return readPly(path);
  if (ext == ".xyz" || ext == ".dat" || ext == ".txt") return readXyz(path);
  if (ext == ".bin") return readKittiBin(path);
  if (ext == ".bz2" || ext == ".gz" || ext == ".xz" || ext == ".zip")
    internal::throwIo(path, "compressed file; decompress it first (e.g. bunzip2 -k)");
  internal::throwIo(path, "unknown point file extension '" + ext +
                              "' (expected .pcd, .ply, .xyz, .dat, .txt or .bin)");
}

}  // namespace fragg
