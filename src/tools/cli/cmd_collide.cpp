// fragg_map collide MAP --waypoints FILE (--box | --sphere | --capsule | --mesh): collision
// checks of a shape at poses (or along a path) against a map, on the CPU or CUDA; --png draws
// the checked poses over the map's top view.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/errors.h"
#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/interop/render.h"
#include "fragg_map/planning/collision_check.h"
#include "fragg_map/planning/path_check.h"
#include "fragg_map/planning/waypoint_file.h"

namespace fragg::cli {

namespace {
struct CollideOptions {
  std::string map, waypoints, mesh, backend = "auto", png;
  std::vector<double> box, capsule;
  double sphere = 0.0, mesh_scale = 1.0, margin_m = 0.0;
  bool path = false, unknown_occupied = false, count_cells = false, json = false;
  int threads = 0;
};

planning::CollisionShape shapeFrom(const CollideOptions& o, const CLI::App& c) {
  const int given = int(!o.box.empty()) + int(c.count("--sphere") > 0) + int(!o.capsule.empty()) +
                    int(!o.mesh.empty());
  if (given != 1)
    throw InvalidArgument("give exactly one shape: --box, --sphere, --capsule or --mesh");
  if (!o.box.empty())
    return planning::CollisionShape::box(0.5 * Eigen::Vector3d(o.box[0], o.box[1], o.box[2]));
  if (c.count("--sphere")) return planning::CollisionShape::sphere(o.sphere);
  if (!o.capsule.empty()) return planning::CollisionShape::capsule(o.capsule[0], o.capsule[1]);
  if (!(o.mesh_scale > 0.0) || !std::isfinite(o.mesh_scale))
    throw InvalidArgument(fmt::format("--mesh-scale must be finite and > 0, got {}", o.mesh_scale));
  const geometry::TriangleMesh mesh = geometry::readObj(o.mesh);  // IoError: exit 1
  try {
    return planning::CollisionShape::mesh(mesh, o.mesh_scale);
  } catch (const InvalidArgument& e) {
    throw IoError(fmt::format("{}: {}", o.mesh, e.what()));  // a bad file, not a bad flag
  }
}

/// The shape's outline seen from above at a pose: the box's (or mesh's bounding box's) footprint,
/// a circle for spheres, the capsule's end circles and sides.
void drawFootprint(RenderImage& image, const planning::CollisionShape& shape,
                   const Eigen::Isometry3d& T, const Rgb& color) {
  const auto polygon = [&](const std::vector<Eigen::Vector3d>& shape_points) {
    for (size_t i = 0; i < shape_points.size(); ++i)
      image.drawLine(T * shape_points[i], T * shape_points[(i + 1) % shape_points.size()], color,
                     3.0);
  };
  const auto circle = [&](const Eigen::Vector3d& centre_map, double r) {
    std::vector<Eigen::Vector3d> points;
    for (int k = 0; k < 24; ++k) {
      const double a = 2 * M_PI * k / 24;
      points.push_back(centre_map + r * Eigen::Vector3d(std::cos(a), std::sin(a), 0));
    }
    for (size_t i = 0; i < points.size(); ++i)
      image.drawLine(points[i], points[(i + 1) % points.size()], color, 3.0);
  };
  Eigen::Vector3d half = shape.halfExtents();
  switch (shape.kind()) {
    case planning::ShapeKind::kSphere:
      circle(T.translation(), shape.radius());
      return;
    case planning::ShapeKind::kCapsule: {
      const Eigen::Vector3d axis = T.linear().col(2) * (0.5 * shape.length());
      circle(T.translation() - axis, shape.radius());
      circle(T.translation() + axis, shape.radius());
      image.drawLine(T.translation() - axis, T.translation() + axis, color, 3.0);
      return;
    }
    case planning::ShapeKind::kMesh: {
      const Eigen::AlignedBox3f b = shape.meshBvh()->bounds();
      const Eigen::Vector3d lo = b.min().cast<double>(), hi = b.max().cast<double>();
      polygon({{lo.x(), lo.y(), 0}, {hi.x(), lo.y(), 0}, {hi.x(), hi.y(), 0}, {lo.x(), hi.y(), 0}});
      return;
    }
    case planning::ShapeKind::kBox:
      polygon({{-half.x(), -half.y(), 0},
               {half.x(), -half.y(), 0},
               {half.x(), half.y(), 0},
               {-half.x(), half.y(), 0}});
      return;
  }
}

/// The map's top view (as `fragg_map render` draws it) around the waypoints, each pose's
/// footprint green when free and red when colliding, the path's segments and its first
/// collision in path mode.
void writeCollisionPng(const std::string& path_png, const Map& map,
                       const planning::CollisionShape& shape,
                       const std::vector<Eigen::Isometry3d>& poses,
                       const std::vector<planning::CollisionResult>& results,
                       const std::optional<planning::PathResult>& path) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Isometry3d& T : poses) box.extend(T.translation());
  const double pad_m = shape.boundingRadius() + 2.0;
  const KeyBounds bounds = map.bounds();
  RenderOptions options;
  options.crop = Eigen::AlignedBox3d(
      Eigen::Vector3d(box.min().x() - pad_m, box.min().y() - pad_m,
                      bounds.empty ? box.min().z() : map.centerOf(bounds.min).z()),
      Eigen::Vector3d(box.max().x() + pad_m, box.max().y() + pad_m,
                      bounds.empty ? box.max().z() : map.centerOf(bounds.max).z()));
  const double side_vox = (options.crop->sizes().head<2>() / map.resolution()).maxCoeff();
  options.scale = std::clamp(static_cast<int>(1000.0 / std::max(side_vox, 1.0)), 1, 16);
  RenderImage image = renderTopDownImage(map, options);
  const Rgb kFree{40, 200, 60}, kHit{235, 30, 30}, kPath{255, 255, 255};
  if (path)
    for (size_t i = 0; i + 1 < poses.size(); ++i)
      image.drawLine(poses[i].translation(), poses[i + 1].translation(), kPath, 2.0);
  for (size_t i = 0; i < poses.size(); ++i)
    drawFootprint(image, shape, poses[i], results[i].collides ? kHit : kFree);
  if (path && path->collides) {
    drawFootprint(image, shape, path->T_map_shape_hit, kHit);
    image.fillDisc(path->T_map_shape_hit.translation(), 1.5 * map.resolution(), kHit);
  }
  writePng(image, path_png);
}

void runCollide(const CollideOptions& o, const CLI::App& c) {
  std::string why;
  const Backend backend = planning::resolveCollisionBackend(backendFromString(o.backend), &why);
  if (!o.png.empty()) {
    if (extensionOf(o.png) != "png")
      throw InvalidArgument(fmt::format("--png must name a .png file, got '{}'", o.png));
    checkOutputDirectory(o.png);
  }
  planning::CollisionOptions options;
  options.unknown_is_occupied = o.unknown_occupied;
  options.margin_m = o.margin_m;
  options.count_cells = o.count_cells;
  options.threads = o.threads;
  planning::validate(options);
  const planning::CollisionShape shape = shapeFrom(o, c);
  const std::vector<Eigen::Isometry3d> poses = planning::readWaypoints(o.waypoints);
  if (poses.empty()) throw IoError(o.waypoints + " holds no waypoints");
  const Map map = loadMapFile(o.map);
  // After the inputs were accepted: a refused input still gets exactly one line.
  if (o.backend == "auto" && backend == Backend::kCpu) std::fprintf(stderr, "%s\n", why.c_str());

  const auto start = std::chrono::steady_clock::now();
  const std::vector<planning::CollisionResult> results =
      planning::checkPoses(map, shape, poses, options, backend);
  std::optional<planning::PathResult> path;
  if (o.path)
    path = planning::checkPath(map, shape, poses, options, planning::PathOptions(), backend);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  if (!o.png.empty()) writeCollisionPng(o.png, map, shape, poses, results, path);

  int64_t first = -1, colliding = 0;
  std::vector<bool> collides(results.size());
  std::vector<uint64_t> cells(results.size());
  for (size_t i = 0; i < results.size(); ++i) {
    collides[i] = results[i].collides;
    cells[i] = results[i].colliding_cells;
    if (!collides[i]) continue;
    ++colliding;
    if (first < 0) first = static_cast<int64_t>(i);
  }
  if (o.json) {
    nlohmann::json j = {{"waypoints", poses.size()},
                        {"collides", collides},
                        {"colliding", colliding},
                        {"first_collision", first},
                        {"ms", ms},
                        {"shape", shape.describe()},
                        {"backend", toString(backend)},
                        {"backend_reason", why}};
    if (first >= 0) {
      const VoxelKey& k = results[first].first_cell;
      j["first_cell"] = {k.x, k.y, k.z};
    }
    if (o.count_cells) j["colliding_cells"] = cells;
    if (path) {
      j["path_collides"] = path->collides;
      j["path_first_segment"] = path->first_segment;
      j["path_fraction"] = path->fraction;
      j["path_poses_checked"] = path->poses_checked;
      if (path->collides) {
        const VoxelKey& k = path->hit.first_cell;
        j["path_cell"] = {k.x, k.y, k.z};
      }
    }
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("%s\n", fmt::format("{} of {} waypoints collide (first: {}), {}, {:.2f} ms on {}",
                                  colliding, poses.size(), first, shape.describe(), ms,
                                  backend == Backend::kCuda ? "CUDA" : "the CPU")
                          .c_str());
  if (path) {
    if (path->collides)
      std::printf("%s\n", fmt::format("path collides on segment {} at fraction {:.4f} ({} poses "
                                      "checked)",
                                      path->first_segment, path->fraction, path->poses_checked)
                              .c_str());
    else
      std::printf("%s\n",
                  fmt::format("path is clear ({} poses checked)", path->poses_checked).c_str());
  }
}
}  // namespace

void addCollideCommand(CLI::App& app) {
  auto o = std::make_shared<CollideOptions>();
  CLI::App* c = app.add_subcommand(
      "collide",
      "Check a shape at poses (or along the path through them) against a map: occupied cells "
      "it overlaps with positive volume collide (touching does not)");
  c->add_option("map", o->map, "Map (.fgm, or .bt / .ot)")->required();
  c->add_option("--waypoints", o->waypoints,
                "Poses, one a line: x y z qx qy qz qw (T_map_shape: the shape's centre or "
                "mesh origin), '#' comments")
      ->required();
  c->add_option("--box", o->box, "Box full lengths LX LY LZ (metres)")->expected(3);
  c->add_option("--sphere", o->sphere, "Sphere radius (metres)");
  c->add_option("--capsule", o->capsule,
                "Capsule radius R and length L of its axis (shape z, centred), metres")
      ->expected(2);
  c->add_option("--mesh", o->mesh, "Triangle mesh (.obj); closed meshes count the cells inside");
  c->add_option("--mesh-scale", o->mesh_scale, "Scale applied to the mesh's coordinates")
      ->capture_default_str();
  c->add_flag("--path", o->path,
              "Also check the path through the waypoints (steps of half a voxel, 0.05 rad)");
  c->add_flag("--unknown-occupied", o->unknown_occupied, "Unknown cells count as occupied");
  c->add_option("--margin", o->margin_m,
                "Grow the shape by M metres (a mesh: each cell grown by M instead)")
      ->capture_default_str();
  c->add_flag("--count-cells", o->count_cells, "Count every colliding cell of each pose");
  c->add_option("--threads", o->threads, "CPU threads (0 = every core)")->capture_default_str();
  c->add_option("--backend", o->backend,
                "auto (CUDA when built with it and a device is present) | cpu | cuda")
      ->capture_default_str();
  c->add_option("--png", o->png,
                "Draw the map's top view around the waypoints with each pose green (free) or red "
                "(colliding), and the path in path mode");
  c->add_flag("--json", o->json, "Print one JSON object on stdout");
  c->callback([o, c] { runCollide(*o, *c); });
}

}  // namespace fragg::cli
