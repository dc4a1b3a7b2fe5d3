#include "fragg_map/sim/scene.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/sim/primitives.h"
#include "scene_tiles.h"

namespace fragg::sim {
namespace {

using geometry::TriangleMesh;
using nlohmann::json;

// Solids standing on the ground reach this far below it, so that no gap opens on a slope.
constexpr double kEmbedM = 0.3;

double num(const json& j, const char* key, double fallback) {
  if (!j.contains(key)) return fallback;
  if (!j.at(key).is_number()) throw InvalidArgument(std::string("'") + key + "' must be a number");
  return j.at(key).get<double>();
}

double required(const json& j, const char* key) {
  if (!j.contains(key)) throw InvalidArgument(std::string("missing '") + key + "'");
  return num(j, key, 0.0);
}

Eigen::VectorXd vec(const json& j, const char* key, int min_n, int max_n) {
  if (!j.contains(key)) throw InvalidArgument(std::string("missing '") + key + "'");
  const json& a = j.at(key);
  if (!a.is_array() || int(a.size()) < min_n || int(a.size()) > max_n)
    throw InvalidArgument(std::string("'") + key + "' must be an array of " +
                          std::to_string(min_n) + ".." + std::to_string(max_n) + " numbers");
  Eigen::VectorXd v(a.size());
  for (size_t i = 0; i < a.size(); ++i) {
    if (!a[i].is_number()) throw InvalidArgument(std::string("'") + key + "' must hold numbers");
    v[i] = a[i].get<double>();
  }
  return v;
}

Terrain readTerrain(const json& g) {
  Terrain t;
  t.present = true;
  const Eigen::VectorXd extent = vec(g, "extent", 4, 4);  // x0 y0 x1 y1
  t.x0_m = extent[0];
  t.y0_m = extent[1];
  t.x1_m = extent[2];
  t.y1_m = extent[3];
  t.base_z_m = num(g, "z", 0.0);
  if (g.contains("slope")) {
    const Eigen::VectorXd s = vec(g, "slope", 2, 2);
    t.slope_x = s[0];
    t.slope_y = s[1];
  }
  t.bump_amplitude_m = num(g, "bump_amplitude", 0.0);
  t.bump_wavelength_m = num(g, "bump_wavelength", 20.0);
  t.cell_m = num(g, "cell", 1.0);
  t.thickness_m = num(g, "thickness", 1.0);
  if (!(t.bump_wavelength_m > 0)) throw InvalidArgument("'bump_wavelength' must be > 0");
  return t;
}

// Lowest terrain height over the footprint corners and centre.
double groundUnder(const Terrain& t, double x0, double y0, double x1, double y1) {
  double z = t.heightAt(0.5 * (x0 + x1), 0.5 * (y0 + y1));
  for (double x : {x0, x1})
    for (double y : {y0, y1}) z = std::min(z, t.heightAt(x, y));
  return z;
}

TriangleMesh readObject(const json& o, const Terrain& terrain, const std::string& base_dir) {
  const std::string type = o.value("type", "");
  if (type == "box") {
    const Eigen::VectorXd lo = vec(o, "min", 3, 3), hi = vec(o, "max", 3, 3);
    return makeBox(lo, hi);
  }
  if (type == "building") {  // axis-aligned box standing on the ground
    const Eigen::VectorXd f = vec(o, "footprint", 4, 4);
    const double h = required(o, "height");
    const double z0 = groundUnder(terrain, f[0], f[1], f[2], f[3]);
    const double top = terrain.heightAt(0.5 * (f[0] + f[2]), 0.5 * (f[1] + f[3])) + h;
    return makeBox(Eigen::Vector3d(f[0], f[1], z0 - kEmbedM), Eigen::Vector3d(f[2], f[3], top));
  }
  if (type == "wall") {  // thin oriented box between two ground points
    const Eigen::VectorXd a = vec(o, "from", 2, 2), b = vec(o, "to", 2, 2);
    const double h = required(o, "height"), thick = num(o, "thickness", 0.3);
    const Eigen::Vector2d d = b - a;
    if (d.norm() <= 0) throw InvalidArgument("wall: 'from' and 'to' must differ");
    const double z0 = std::min(terrain.heightAt(a[0], a[1]), terrain.heightAt(b[0], b[1]));
    const double z_top = std::max(terrain.heightAt(a[0], a[1]), terrain.heightAt(b[0], b[1])) + h;
    const double bottom = z0 - kEmbedM;
    const Eigen::Vector3d centre(0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (bottom + z_top));
    return makeOrientedBox(centre,
                           Eigen::Vector3d(0.5 * d.norm(), 0.5 * thick, 0.5 * (z_top - bottom)),
                           std::atan2(d.y(), d.x()));
  }
  if (type == "tree") {  // trunk (cylinder) + crown (sphere), two solids
    const Eigen::VectorXd at = vec(o, "at", 2, 2);
    const double r_trunk = num(o, "trunk_radius", 0.2), h_trunk = num(o, "trunk_height", 3.0);
    const double r_crown = num(o, "crown_radius", 2.0);
    const double z = terrain.heightAt(at[0], at[1]);
    TriangleMesh tree;
    tree.appendSolid(makeCylinder(Eigen::Vector3d(at[0], at[1], z - kEmbedM),
                                  Eigen::Vector3d(at[0], at[1], z + h_trunk + 0.5 * r_crown),
                                  r_trunk, 12));
    tree.appendSolid(
        makeSphere(Eigen::Vector3d(at[0], at[1], z + h_trunk + r_crown), r_crown, 10, 16));
    return tree;
  }
  if (type == "cylinder" || type == "pipe") {
    const Eigen::VectorXd a = vec(o, "from", 3, 3), b = vec(o, "to", 3, 3);
    return makeCylinder(a, b, required(o, "radius"), static_cast<int>(num(o, "segments", 24)));
  }
  if (type == "sphere") {
    return makeSphere(vec(o, "centre", 3, 3), required(o, "radius"));
  }
  if (type == "mesh") {
    if (!o.contains("obj") || !o.at("obj").is_string())
      throw InvalidArgument("mesh: 'obj' must name an OBJ file");
    std::string path = o.at("obj").get<std::string>();
    if (!path.empty() && path[0] != '/') path = base_dir + "/" + path;
    TriangleMesh m = geometry::readObj(path);
    if (o.contains("offset")) {
      const Eigen::Vector3f off = vec(o, "offset", 3, 3).cast<float>();
      for (Eigen::Vector3f& v : m.vertices_m) v += off;
    }
    return m;
  }
  throw InvalidArgument("unknown object type '" + type +
                        "' (box, building, wall, tree, cylinder, pipe, sphere, mesh)");
}

TrajectorySpec readTrajectory(const json& t) {
  TrajectorySpec spec;
  if (!t.contains("waypoints") || !t.at("waypoints").is_array())
    throw InvalidArgument("a trajectory needs 'waypoints' (an array of [x, y] or [x, y, z])");
  for (const json& w : t.at("waypoints")) {
    json wrap = {{"p", w}};
    const Eigen::VectorXd p = vec(wrap, "p", 2, 3);
    spec.waypoints_m.emplace_back(p[0], p[1], p.size() > 2 ? p[2] : 0.0);
  }
  spec.speed_mps = num(t, "speed", spec.speed_mps);
  spec.rate_hz = num(t, "rate", spec.rate_hz);
  spec.follow_ground = t.value("follow_ground", false);
  spec.closed = t.value("closed", false);
  spec.heading_window_m = num(t, "heading_window", spec.heading_window_m);
  return spec;
}

MoverSpec readMover(const json& o, size_t index) {
  MoverSpec m;
  m.name = o.value("name", "mover" + std::to_string(index));
  m.kind = moverKindFromString(o.value("type", ""));
  switch (m.kind) {
    case MoverKind::kCar:
      m.size_m = Eigen::Vector3d(4.5, 1.8, 1.5);
      m.speed_mps = 5.0;
      break;
    case MoverKind::kDoor:
      m.size_m = Eigen::Vector3d(1.0, 0.08, 2.1);
      break;
    default:
      break;
  }
  if (o.contains("size")) m.size_m = vec(o, "size", 3, 3);
  if (m.kind == MoverKind::kDoor) {
    m.hinge_m = vec(o, "hinge", 2, 2);
    m.closed_yaw_deg = num(o, "closed_yaw", m.closed_yaw_deg);
    m.open_yaw_deg = num(o, "open_yaw", m.open_yaw_deg);
    m.period_s = num(o, "period", m.period_s);
  } else {
    if (!o.contains("path") || !o.at("path").is_array())
      throw InvalidArgument("a mover needs 'path' (an array of [x, y])");
    for (const json& w : o.at("path")) {
      json wrap = {{"p", w}};
      const Eigen::VectorXd p = vec(wrap, "p", 2, 2);
      m.waypoints_m.emplace_back(p[0], p[1]);
    }
    m.speed_mps = num(o, "speed", m.speed_mps);
    if (o.contains("pause")) {
      if (o.at("pause").is_array()) {
        const Eigen::VectorXd p = vec(o, "pause", 1, 100000);
        m.pause_s.assign(p.data(), p.data() + p.size());
      } else {
        m.pause_s = {num(o, "pause", 0.0)};
      }
    }
    const std::string repeat = o.value("repeat", "pingpong");
    if (repeat == "pingpong")
      m.repeat = MoverRepeat::kPingPong;
    else if (repeat == "loop")
      m.repeat = MoverRepeat::kLoop;
    else if (repeat == "once")
      m.repeat = MoverRepeat::kOnce;
    else
      throw InvalidArgument("'repeat' must be pingpong, loop or once, not '" + repeat + "'");
  }
  m.start_s = num(o, "start", 0.0);
  m.validate();
  return m;
}

}  // namespace

double Terrain::heightAt(double x_m, double y_m) const {
  if (!present) return 0.0;
  return base_z_m + slope_x * x_m + slope_y * y_m +
         bump_amplitude_m * std::sin(2 * M_PI * x_m / bump_wavelength_m) *
             std::cos(2 * M_PI * y_m / bump_wavelength_m);
}

Scene sceneFromJson(const std::string& json_text, const std::string& base_dir) {
  json j;
  try {
    j = json::parse(json_text);
  } catch (const json::exception& e) {
    throw IoError(std::string("scene: not valid JSON: ") + e.what());
  }
  j = expandSceneTiles(j, base_dir);
  Scene scene;
  scene.name = j.value("name", "scene");
  if (j.contains("ground")) {
    try {
      scene.terrain = readTerrain(j.at("ground"));
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(std::string("scene ground: ") + e.what());
    }
    const Terrain& t = scene.terrain;
    scene.mesh.append(makeTerrainSlab(t.x0_m, t.y0_m, t.x1_m, t.y1_m, t.cell_m, t.thickness_m,
                                      [&t](double x, double y) { return t.heightAt(x, y); }));
  }
  if (j.contains("objects")) {
    size_t index = 0;
    for (const json& o : j.at("objects")) {
      try {
        scene.mesh.append(readObject(o, scene.terrain, base_dir));
      } catch (const InvalidArgument& e) {
        throw InvalidArgument("scene object " + std::to_string(index) + " (" +
                              o.value("type", "?") + "): " + e.what());
      }
      ++index;
    }
  }
  if (j.contains("movers")) {
    size_t index = 0;
    for (const json& o : j.at("movers")) {
      try {
        scene.movers.push_back(readMover(o, index));
      } catch (const InvalidArgument& e) {
        throw InvalidArgument("scene mover " + std::to_string(index) + " (" + o.value("type", "?") +
                              "): " + e.what());
      }
      ++index;
    }
  }
  if (j.contains("trajectories")) {
    for (const auto& [name, t] : j.at("trajectories").items()) {
      try {
        scene.trajectories[name] = readTrajectory(t);
      } catch (const InvalidArgument& e) {
        throw InvalidArgument("trajectory '" + name + "': " + e.what());
      }
    }
  }
  if (scene.mesh.empty()) throw InvalidArgument("scene has no objects and no ground");
  return scene;
}

Scene loadScene(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path + ": cannot open scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  const size_t slash = path.find_last_of('/');
  try {
    return sceneFromJson(ss.str(), slash == std::string::npos ? "." : path.substr(0, slash));
  } catch (const IoError& e) {
    throw IoError(path + ": " + e.what());
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(path + ": " + e.what());
  }
}

}  // namespace fragg::sim
