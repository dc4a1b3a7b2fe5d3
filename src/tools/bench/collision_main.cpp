// fragg_map_collision_bench: collision batches on a map (issue 15's speed goals). Loads a .fgm,
// draws deterministic random poses (robot-like: x, y over the map's observed area, z in the
// lowest 3 m above its floor, yaw only), and times one batch per shape on each backend:
// box (default 0.6 x 0.6 x 0.4 m) and sphere and capsule, 100,000 poses each; a closed
// ellipsoid mesh (semi-axes 0.35, 0.3, 0.25 m) of 4,900 triangles, 1,000 poses. With FCL found at
// build time, FCL's OcTree collision (the map's occupied cells in an octomap::OcTree) runs on the
// same box poses.
//
// On CUDA, box, sphere and capsule poses are prepared on the host (the library's default) or
// on the device (--pose-prep device; `both` alternates the two batch by batch in one process,
// each timed and printed apart, answers compared).
//
//   fragg_map_collision_bench --map W1.fgm [--poses 100000] [--mesh-poses 1000]
//       [--backends cpu cuda] [--repeats 3] [--fcl-poses 20000] [--json FILE]
//       [--pose-prep host|device|both] [--chunk-poses 0 ...]
#include <fmt/format.h>
#include <omp.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_primitives.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/collision_check.h"

#if FRAGG_HAVE_FCL
#include <fcl/fcl.h>
#include <octomap/OcTree.h>
#endif

namespace fragg::bench {
namespace {

struct Options {
  std::string map_path, json_path;
  size_t poses = 100000, mesh_poses = 1000, fcl_poses = 20000;
  std::vector<double> box = {0.6, 0.6, 0.4};
  std::vector<std::string> backends = {"cpu", "cuda"};
  std::vector<std::string> shapes = {"box", "sphere", "capsule", "mesh"};
  int repeats = 3;
  uint32_t seed = 15;
  std::string pose_prep = "host";
  std::vector<size_t> chunk_poses = {0};  ///< device preparation: one run per value
};

/// One way of running a CUDA batch: where poses are prepared, and its chunk size.
struct Prep {
  std::string label;  ///< "" for the library's default (host)
  planning::CollisionOptions options;
};

/// The ways the options ask for: host and/or device (one per chunk size).
std::vector<Prep> prepsOf(const Options& o) {
  std::vector<Prep> out;
  if (o.pose_prep == "host" || o.pose_prep == "both") out.push_back({"host", {}});
  if (o.pose_prep == "device" || o.pose_prep == "both")
    for (const size_t chunk : o.chunk_poses) {
      Prep p{chunk ? fmt::format("device/{}", chunk) : "device", {}};
      p.options.pose_preparation = planning::PosePreparation::kDevice;
      p.options.device_chunk_poses = chunk;
      out.push_back(p);
    }
  if (out.empty()) throw InvalidArgument("--pose-prep must be host, device or both");
  return out;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// Poses over the observed x/y area, z in [floor + 0.25, floor + 3] m, random yaw.
std::vector<Eigen::Isometry3d> randomPoses(const Map& map, size_t n, uint32_t seed) {
  const KeyBounds b = map.bounds();
  const Eigen::Vector3d lo = map.centerOf(b.min), hi = map.centerOf(b.max);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uy(lo.y(), hi.y()),
      uz(lo.z() + 0.25, std::min(hi.z(), lo.z() + 3.0)), uyaw(-M_PI, M_PI);
  std::vector<Eigen::Isometry3d> out(n);
  for (Eigen::Isometry3d& T : out) {
    T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(ux(rng), uy(rng), uz(rng));
    T.linear() = Eigen::AngleAxisd(uyaw(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  }
  return out;
}

struct Run {
  std::string shape, backend;
  size_t poses = 0, colliding = 0;
  double ms_median = 0, ms_min = 0;
  planning::CollisionStages stages;  ///< median of each stage over the repeats
};

using Batch =
    std::function<std::vector<planning::CollisionResult>(const planning::CollisionOptions&)>;

/// `batch` run `repeats` times each way of `preps`, the ways alternated batch by batch (so that
/// drifts of the machine hit them alike); one Run (median, min) and the last answers per way.
std::vector<Run> timeBatches(const Batch& batch, const std::string& name, Backend backend,
                             const std::vector<Prep>& preps, int repeats, size_t n_poses,
                             std::vector<std::vector<planning::CollisionResult>>* answers) {
  std::vector<std::vector<double>> ms(preps.size());
  std::vector<std::vector<planning::CollisionStages>> stages(preps.size());
  answers->assign(preps.size(), {});
  for (int r = 0; r < repeats; ++r)
    for (size_t p = 0; p < preps.size(); ++p) {
      planning::CollisionOptions options = preps[p].options;
      planning::CollisionStages s;
      options.stages = &s;
      const auto t0 = std::chrono::steady_clock::now();
      (*answers)[p] = batch(options);
      ms[p].push_back(msSince(t0));
      stages[p].push_back(s);
    }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::vector<Run> runs;
  for (size_t p = 0; p < preps.size(); ++p) {
    std::sort(ms[p].begin(), ms[p].end());
    std::string label = toString(backend);
    if (preps.size() > 1 || !preps[p].label.empty()) label += "/" + preps[p].label;
    Run run{name, label, n_poses, 0, ms[p][ms[p].size() / 2], ms[p].front(), {}};
    auto stage = [&](double planning::CollisionStages::*field) {
      std::vector<double> v;
      for (const planning::CollisionStages& s : stages[p]) v.push_back(s.*field);
      return median(v);
    };
    run.stages.validate_ms = stage(&planning::CollisionStages::validate_ms);
    run.stages.obstacles_ms = stage(&planning::CollisionStages::obstacles_ms);
    run.stages.poses_ms = stage(&planning::CollisionStages::poses_ms);
    run.stages.device_ms = stage(&planning::CollisionStages::device_ms);
    run.stages.results_ms = stage(&planning::CollisionStages::results_ms);
    for (const auto& a : (*answers)[p]) run.colliding += a.collides;
    runs.push_back(run);
  }
  return runs;
}

/// Poses whose answers differ between `a` and `b` (collides, or the first cell where both
/// collide).
size_t differing(const std::vector<planning::CollisionResult>& a,
                 const std::vector<planning::CollisionResult>& b) {
  size_t differ = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i)
    differ +=
        a[i].collides != b[i].collides || (a[i].collides && a[i].first_cell != b[i].first_cell);
  return differ + (a.size() > b.size() ? a.size() - b.size() : b.size() - a.size());
}

#if FRAGG_HAVE_FCL
/// FCL's OcTree collision of a box at each pose against the map's occupied cells (one leaf
/// per occupied cell in an octomap::OcTree of the map's resolution), on omp threads.
Run timeFcl(const Map& map, const Eigen::Vector3d& box_m,
            const std::vector<Eigen::Isometry3d>& poses,
            const std::vector<planning::CollisionResult>& ours, size_t* agree) {
  auto tree = std::make_shared<octomap::OcTree>(map.resolution());
  map.forEachBlock([&](const BlockKey& key, const Block& block) {
    for (int i = 0; i < kCellsPerBlock; ++i) {
      if (map.state(block.cells[i]) != CellState::kOccupied) continue;
      const Eigen::Vector3d c = map.centerOf(voxelKeyOf(key, i));
      tree->updateNode(octomap::point3d(float(c.x()), float(c.y()), float(c.z())), true);
    }
  });
  tree->updateInnerOccupancy();
  auto fcl_tree = std::make_shared<fcl::OcTreed>(tree);
  const fcl::CollisionObjectd tree_object(fcl_tree);
  auto box = std::make_shared<fcl::Boxd>(box_m);
  std::vector<uint8_t> hit(poses.size(), 0);
  const auto t0 = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(dynamic, 64)
  for (int64_t i = 0; i < static_cast<int64_t>(poses.size()); ++i) {
    fcl::Transform3d T = fcl::Transform3d::Identity();
    T.linear() = poses[i].linear();
    T.translation() = poses[i].translation();
    const fcl::CollisionObjectd box_object(box, T);
    fcl::CollisionRequestd request;
    fcl::CollisionResultd result;
    fcl::collide(&box_object, &tree_object, request, result);
    hit[i] = result.isCollision();
  }
  Run run{"box", "fcl-octree", poses.size(), 0, msSince(t0), 0, {}};
  run.ms_min = run.ms_median;
  *agree = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    run.colliding += hit[i];
    *agree += (hit[i] != 0) == ours[i].collides;
  }
  return run;
}
#endif

void run(const Options& o) {
  const auto t_load = std::chrono::steady_clock::now();
  const Map map = Map::load(o.map_path, Backend::kCpu);
  fmt::print("map {}: {} blocks, {} m, loaded in {:.0f} ms; {} threads\n", o.map_path,
             map.blockCount(), map.resolution(), msSince(t_load), omp_get_max_threads());
  const std::vector<Eigen::Isometry3d> poses = randomPoses(map, o.poses, o.seed);
  // The same map on the CUDA backend, where CUDA checks read its state masks in place through
  // the device layer view (no obstacle index, no upload of masks): loaded when cuda is asked
  // for and a device is there.
  std::unique_ptr<Map> cuda_map;
  if (std::find(o.backends.begin(), o.backends.end(), "cuda") != o.backends.end()) {
    std::string why_not;
    if (!cudaDeviceName(0, &why_not).empty())
      cuda_map = std::make_unique<Map>(Map::load(o.map_path, Backend::kCuda));
  }
  const std::vector<Eigen::Isometry3d> mesh_poses = randomPoses(map, o.mesh_poses, o.seed + 1);
  const Eigen::Vector3d box_m(o.box[0], o.box[1], o.box[2]);
  const geometry::TriangleMesh mesh =
      geometry::ellipsoidMesh(Eigen::Vector3f(0.35f, 0.3f, 0.25f), 50, 50);
  struct Case {
    std::string key, name;
    planning::CollisionShape shape;
    const std::vector<Eigen::Isometry3d>* poses;
  };
  std::vector<Case> cases = {
      {"box", fmt::format("box {}x{}x{} m", o.box[0], o.box[1], o.box[2]),
       planning::CollisionShape::box(0.5 * box_m), &poses},
      {"sphere", "sphere r 0.3 m", planning::CollisionShape::sphere(0.3), &poses},
      {"capsule", "capsule r 0.2 m L 0.6 m", planning::CollisionShape::capsule(0.2, 0.6), &poses},
      {"mesh", fmt::format("closed ellipsoid mesh, {} triangles", mesh.size()),
       planning::CollisionShape::mesh(mesh), &mesh_poses}};

  cases.erase(std::remove_if(cases.begin(), cases.end(),
                             [&](const Case& c) {
                               return std::find(o.shapes.begin(), o.shapes.end(), c.key) ==
                                      o.shapes.end();
                             }),
              cases.end());
  nlohmann::json j = {{"map", o.map_path}, {"threads", omp_get_max_threads()}, {"runs", {}}};
  {
    // The fixed cost of a batch that spans the whole map: two poses at opposite corners make
    // the batch classify every block's cells (the obstacle masks) and check almost nothing.
    const KeyBounds b = map.bounds();
    std::vector<Eigen::Isometry3d> corners(2, Eigen::Isometry3d::Identity());
    corners[0].translation() = map.centerOf(b.min);
    corners[1].translation() = map.centerOf(b.max);
    std::vector<double> ms;
    for (int r = 0; r < o.repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      planning::checkPoses(map, planning::CollisionShape::sphere(0.05), corners,
                           planning::CollisionOptions(), Backend::kCpu);
      ms.push_back(msSince(t0));
    }
    std::sort(ms.begin(), ms.end());
    fmt::print("obstacle masks of the whole map (a 2-pose batch spanning it): {:.1f} ms\n",
               ms[ms.size() / 2]);
    j["whole_map_masks_ms"] = ms[ms.size() / 2];
  }
  std::vector<planning::CollisionResult> box_cpu;
  fmt::print("{:<40} {:>8} {:>8} {:>10} {:>10} {:>12}\n", "shape", "backend", "poses", "colliding",
             "ms median", "poses/s");
  const std::vector<Prep> preps = prepsOf(o);
  for (const Case& c : cases) {
    std::vector<std::vector<planning::CollisionResult>> per_backend;
    for (const std::string& name : o.backends) {
      const Backend requested = backendFromString(name);
      std::string why;
      Backend use = Backend::kCpu;
      try {
        use = planning::resolveCollisionBackend(requested, &why);
      } catch (const InvalidArgument& e) {
        fmt::print("{:<40} {:>8} skipped: {}\n", c.name, name, e.what());
        continue;
      }
      // Where poses are prepared matters on CUDA for boxes, spheres and capsules only.
      const std::vector<Prep> ways =
          use == Backend::kCuda && c.key != "mesh" ? preps : std::vector<Prep>{Prep{"", {}}};
      // One line per way; every way's answers against `reference` (none: against the first).
      auto report = [&](const std::vector<Run>& runs,
                        const std::vector<std::vector<planning::CollisionResult>>& answers,
                        const std::vector<planning::CollisionResult>* reference,
                        const std::string& note, const std::string& json_suffix,
                        nlohmann::json extra) {
        for (size_t p = 0; p < runs.size(); ++p) {
          const Run& r = runs[p];
          std::string line_note = note;
          size_t differ = 0;
          if (reference || p > 0) {
            differ = differing(reference ? *reference : answers[0], answers[p]);
            line_note += fmt::format("{}{} answers differ", line_note.empty() ? "" : "; ", differ);
          }
          fmt::print("{:<40} {:>8} {:>8} {:>10} {:>10.2f} {:>12.3g}{}\n", r.shape, r.backend,
                     r.poses, r.colliding, r.ms_median, r.poses / (r.ms_median * 1e-3),
                     line_note.empty() ? "" : "  " + line_note);
          const planning::CollisionStages& st = r.stages;
          fmt::print(
              "{:<40} stages, median ms: validate {:.3f}, obstacles {:.3f}, poses {:.3f}, "
              "device {:.3f}, results {:.3f}\n",
              "", st.validate_ms, st.obstacles_ms, st.poses_ms, st.device_ms, st.results_ms);
          nlohmann::json run = {{"shape", r.shape},
                                {"backend", r.backend + json_suffix},
                                {"poses", r.poses},
                                {"colliding", r.colliding},
                                {"ms_median", r.ms_median},
                                {"ms_min", r.ms_min},
                                {"differ", differ},
                                {"stages_ms",
                                 {{"validate", r.stages.validate_ms},
                                  {"obstacles", r.stages.obstacles_ms},
                                  {"poses", r.stages.poses_ms},
                                  {"device", r.stages.device_ms},
                                  {"results", r.stages.results_ms}}}};
          run.update(extra);
          j["runs"].push_back(run);
        }
      };
      std::vector<std::vector<planning::CollisionResult>> answers;
      const std::vector<Run> runs = timeBatches(
          [&](const planning::CollisionOptions& opt) {
            return planning::checkPoses(map, c.shape, *c.poses, opt, requested);
          },
          c.name, requested, ways, o.repeats, c.poses->size(), &answers);
      report(runs, answers, nullptr, "", "", nlohmann::json::object());
      if (c.key == "box" && requested == Backend::kCpu) box_cpu = answers[0];
      per_backend.push_back(answers[0]);
      if (use == Backend::kCuda && cuda_map) {
        // A map integrating on CUDA: the first batch brings its blocks to the device (timed
        // apart), then batches read them in place.
        const auto t_first = std::chrono::steady_clock::now();
        (void)planning::checkPoses(*cuda_map, c.shape, *c.poses, ways[0].options, Backend::kCuda);
        const double first_ms = msSince(t_first);
        std::vector<std::vector<planning::CollisionResult>> on_view;
        const std::vector<Run> v = timeBatches(
            [&](const planning::CollisionOptions& opt) {
              return planning::checkPoses(*cuda_map, c.shape, *c.poses, opt, Backend::kCuda);
            },
            c.name, Backend::kCuda, ways, o.repeats, c.poses->size(), &on_view);
        report(v, on_view, &per_backend.back(),
               fmt::format("map on CUDA, device layer view (first batch {:.1f} ms)", first_ms),
               "+layer_view", {{"first_batch_ms", first_ms}});
      }
      // The same batch over a map prepared once (PreparedMap: masks of every block kept
      // between batches, as FCL's OcTree is built once), preparation timed apart.
      const auto t_prep = std::chrono::steady_clock::now();
      const planning::PreparedMap prepared(map, false);
      const double prep_ms = msSince(t_prep);
      std::vector<std::vector<planning::CollisionResult>> again;
      const std::vector<Run> pr = timeBatches(
          [&](const planning::CollisionOptions& opt) {
            return planning::checkPoses(prepared, c.shape, *c.poses, opt, requested);
          },
          c.name, requested, ways, o.repeats, c.poses->size(), &again);
      report(pr, again, &per_backend.back(), fmt::format("prepared map ({:.0f} ms once)", prep_ms),
             "+prepared", {{"prepare_ms", prep_ms}});
    }
    // Backends must agree exactly (the gpu test asserts it; the benchmark says so too).
    for (size_t b = 1; b < per_backend.size(); ++b) {
      size_t differ = 0;
      for (size_t i = 0; i < per_backend[0].size(); ++i)
        differ += per_backend[0][i].collides != per_backend[b][i].collides ||
                  (per_backend[0][i].collides &&
                   per_backend[0][i].first_cell != per_backend[b][i].first_cell);
      fmt::print("{:<40} backends differ on {} poses\n", c.name, differ);
    }
  }
#if FRAGG_HAVE_FCL
  if (o.fcl_poses > 0 && !box_cpu.empty()) {
    const size_t n = std::min(o.fcl_poses, poses.size());
    const std::vector<Eigen::Isometry3d> subset(poses.begin(), poses.begin() + n);
    size_t agree = 0;
    const Run r = timeFcl(map, box_m, subset, box_cpu, &agree);
    const double fcl_rate = r.poses / (r.ms_median * 1e-3);
    fmt::print("{:<40} {:>8} {:>8} {:>10} {:>10.2f} {:>12.3g}  (agrees with cpu on {} of {})\n",
               cases.front().name, r.backend, r.poses, r.colliding, r.ms_median, fcl_rate, agree,
               n);
    for (const auto& run : j["runs"])
      if ((run["backend"] == "cpu" || run["backend"] == "cpu+prepared") &&
          run["shape"] == cases.front().name) {
        const double cpu_rate = double(run["poses"]) / (double(run["ms_median"]) * 1e-3);
        const std::string b = run["backend"];
        fmt::print("{} / fcl throughput on the box poses: {:.1f}x\n", b, cpu_rate / fcl_rate);
        j[b + "_over_fcl"] = cpu_rate / fcl_rate;
      }
    j["fcl"] = {{"poses", n}, {"ms", r.ms_median}, {"colliding", r.colliding}, {"agree", agree}};
  }
#else
  fmt::print("FCL not found at build time: no FCL comparison\n");
#endif
  if (!o.json_path.empty()) std::ofstream(o.json_path) << j.dump(2) << "\n";
}

}  // namespace
}  // namespace fragg::bench

int main(int argc, char** argv) {
  fragg::bench::Options o;
  CLI::App app("Collision batches on a map: CPU, CUDA and FCL's OcTree");
  app.add_option("--map", o.map_path, "Map (.fgm)")->required();
  app.add_option("--poses", o.poses, "Box, sphere and capsule poses")->capture_default_str();
  app.add_option("--mesh-poses", o.mesh_poses, "Mesh poses")->capture_default_str();
  app.add_option("--box", o.box, "Box full lengths (metres)")->expected(3)->capture_default_str();
  app.add_option("--backends", o.backends, "cpu cuda (auto too)")->capture_default_str();
  app.add_option("--shapes", o.shapes, "Subset of box sphere capsule mesh")->capture_default_str();
  app.add_option("--repeats", o.repeats, "Batches per shape and backend (median)")
      ->capture_default_str();
  app.add_option("--fcl-poses", o.fcl_poses, "Box poses for FCL (the first N; 0: none)")
      ->capture_default_str();
  app.add_option("--seed", o.seed, "Pose seed")->capture_default_str();
  app.add_option("--json", o.json_path, "Write the figures as JSON");
  app.add_option("--pose-prep", o.pose_prep,
                 "CUDA boxes, spheres, capsules: poses prepared on the host, the device, or both "
                 "(alternated batch by batch)")
      ->check(CLI::IsMember({"host", "device", "both"}))
      ->capture_default_str();
  app.add_option("--chunk-poses", o.chunk_poses,
                 "Device preparation: poses a chunk, one run per value (0: four chunks)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    fragg::bench::run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_collision_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
