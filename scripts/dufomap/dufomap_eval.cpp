// DUFOMap beside fragg_map (issue 37), built by scripts/dufomap_side_by_side.sh in a git-ignored
// scratch folder against the ufomap library that KTH-RPL/dufomap carried in its own tree at
// commit d3df8fc (the last commit before ufomap became a submodule; the submodule's pinned
// commit is not in the ufomap snapshot this project can fetch). Nothing of DUFOMap is copied
// here: this program calls its public integration API the way DUFOMap's dufomap_run does, with
// the parameters of DUFOMap's config (resolution, max range and the two inflation distances from
// the command line), and adds what the side by side needs:
//  * the time of every insertPointCloud (median and mean, ms),
//  * DUFOMap's verdict per point (static: its voxel is not seenFree after the last scan) for the
//    points within max range of their scan's viewpoint, as fragg_map eval --label-max-range counts,
//  * the kept (static) points as float32 x y z triples for kth_io tobt (an OctoMap .bt that
//    fragg_map eval reads), and, with DUFO_LABELS=DATASET, point-level SA and DA from
//    DATASET/labels/NNNNNN.dyn (one byte a finite point, 1 = dynamic, kth_io convert's order).
// Input: PCD_DIR/pcd/NNNNNN.pcd (kth_io convert: map-frame points, VIEWPOINT = sensor pose).
// Usage: dufomap_eval PCD_DIR RES_M MAX_RANGE_M KEPT.xyz [INFLATE_UNKNOWN=1] [INFLATE_HITS_M=0.2]
// Prints one JSON object a line (point_level with DUFO_LABELS, then the run's figures).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <ufo/map/integration/integration.hpp>
#include <ufo/map/integration/integration_parameters.hpp>
#include <ufo/map/point_cloud.hpp>
#include <ufo/map/ufomap.hpp>
#include <ufo/math/pose6.hpp>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// DUFOMap's configuration (assets/config.toml at d3df8fc) with the side by side's resolution,
// range and inflation.
ufo::IntegrationParams dufomapParams(float max_range_m, std::size_t inflate_unknown,
                                     float inflate_hits_m) {
  ufo::IntegrationParams p;
  p.down_sampling_method = ufo::DownSamplingMethod::CENTER;
  p.hit_depth = 0;
  p.miss_depth = 0;
  p.max_range = max_range_m;
  p.only_valid = false;  // points beyond max range clear up to it, as OctoMap and fragg do
  p.inflate_unknown = inflate_unknown;
  p.inflate_unknown_compensation = true;
  p.inflate_hits_dist = inflate_hits_m;
  p.ray_casting_method = ufo::RayCastingMethod::PROPER;
  p.simple_ray_casting_factor = 1.0f;
  p.parallel = true;
  if (const char* t = std::getenv("DUFO_THREADS")) p.num_threads = std::stoul(t);
  return p;
}

std::vector<char> readLabels(const std::filesystem::path& dataset, std::size_t scan) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu.dyn", scan);
  std::ifstream in(dataset / "labels" / name, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open labels of scan " + std::to_string(scan));
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 5 || argc > 7) {
    std::cerr << "usage: dufomap_eval PCD_DIR RES_M MAX_RANGE_M KEPT.xyz [INFLATE_UNKNOWN] "
                 "[INFLATE_HITS_M]\n";
    return 2;
  }
  const std::filesystem::path dir(argv[1]);
  const double res_m = std::stod(argv[2]);
  const float max_range_m = std::stof(argv[3]);
  const ufo::IntegrationParams params = dufomapParams(
      max_range_m, argc > 5 ? std::stoul(argv[5]) : 1, argc > 6 ? std::stof(argv[6]) : 0.2f);
  ufo::Map<ufo::MapType::SEEN_FREE | ufo::MapType::REFLECTION | ufo::MapType::LABEL> map(res_m, 20);
  map.reserve(100'000'000);

  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir / "pcd"))
    if (e.is_regular_file()) files.push_back(e.path());
  std::ranges::sort(files);
  if (files.empty()) throw std::runtime_error(dir.string() + "/pcd holds no scan");

  std::vector<ufo::PointCloud> clouds;
  std::vector<ufo::Point> origins;
  std::vector<double> insert_ms;
  for (const auto& f : files) {
    ufo::PointCloud cloud;
    ufo::Pose6f viewpoint;
    ufo::readPointCloudPCD(f, cloud, viewpoint);
    clouds.push_back(cloud);
    origins.push_back(viewpoint.translation);
    const auto t0 = Clock::now();
    ufo::insertPointCloud(map, cloud, viewpoint.translation, params, false);
    insert_ms.push_back(msSince(t0));
  }
  const auto t0 = Clock::now();
  map.propagateModified();
  const double propagate_ms = msSince(t0);

  const char* labels_dir = std::getenv("DUFO_LABELS");
  std::vector<float> kept;
  std::size_t in_range = 0, removed = 0;
  std::size_t static_points = 0, static_kept = 0, dynamic_points = 0, dynamic_removed = 0;
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    const std::vector<char> labels = labels_dir ? readLabels(labels_dir, i) : std::vector<char>{};
    if (labels_dir && labels.size() != clouds[i].size())
      throw std::runtime_error("scan " + std::to_string(i) + ": label count differs");
    for (std::size_t k = 0; k < clouds[i].size(); ++k) {
      const auto& pt = clouds[i][k];
      if (origins[i].distance(pt) > max_range_m) continue;
      ++in_range;
      const bool seen_free = map.seenFree(pt);
      if (labels_dir && labels[k]) {
        ++dynamic_points;
        dynamic_removed += seen_free;
      } else if (labels_dir) {
        ++static_points;
        static_kept += !seen_free;
      }
      if (seen_free) {
        ++removed;
        continue;
      }
      kept.insert(kept.end(), {pt.x, pt.y, pt.z});
    }
  }
  std::ofstream(argv[4], std::ios::binary)
      .write(reinterpret_cast<const char*>(kept.data()),
             static_cast<std::streamsize>(kept.size() * sizeof(float)));

  if (labels_dir)
    std::printf(
        "{\"point_level\": {\"static_points\": %zu, \"static_kept\": %zu, \"dynamic_points\": "
        "%zu, \"dynamic_removed\": %zu, \"sa\": %.6f, \"da\": %.6f}}\n",
        static_points, static_kept, dynamic_points, dynamic_removed,
        static_points ? double(static_kept) / static_points : 0.0,
        dynamic_points ? double(dynamic_removed) / dynamic_points : 0.0);
  std::vector<double> sorted = insert_ms;
  std::ranges::sort(sorted);
  double sum = 0;
  for (double m : insert_ms) sum += m;
  std::printf(
      "{\"scans\": %zu, \"ms_per_scan\": {\"median\": %.3f, \"mean\": %.3f}, \"propagate_ms\": "
      "%.3f, \"points_in_range\": %zu, \"points_removed\": %zu, \"threads\": %zu}\n",
      insert_ms.size(), sorted[sorted.size() / 2], sum / insert_ms.size(), propagate_ms, in_range,
      removed, params.num_threads);
  return 0;
} catch (const std::exception& e) {
  std::cerr << "dufomap_eval: " << e.what() << "\n";
  return 1;
}
