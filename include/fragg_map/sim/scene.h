// A simulated scene: closed solids (ground slab, buildings, walls, trees, pipes, spheres, OBJ
// meshes), moving objects ("movers": pedestrians, cars, doors) and named trajectories, read from a
// JSON scene file (config/scenes/*.json; the format is described in docs/cli.md, "Simulator").
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fragg_map/geometry/triangle_mesh.h"
#include "fragg_map/sim/movers.h"
#include "fragg_map/sim/trajectory.h"

namespace fragg::sim {

/// Terrain height: base + slope * (x, y) + amplitude * sin(2 pi x / L) * cos(2 pi y / L).
struct Terrain {
  bool present = false;
  double x0_m = 0, y0_m = 0, x1_m = 0, y1_m = 0;
  double base_z_m = 0;
  double slope_x = 0, slope_y = 0;  ///< metres per metre
  double bump_amplitude_m = 0;
  double bump_wavelength_m = 20;
  double cell_m = 1;       ///< mesh grid of the top surface
  double thickness_m = 1;  ///< of the slab below the lowest point

  /// Terrain height at (x, y); 0 when there is no terrain.
  double heightAt(double x_m, double y_m) const;
};

struct Scene {
  std::string name;
  Terrain terrain;
  geometry::TriangleMesh mesh;    ///< every static object, closed solids (the static truth)
  std::vector<MoverSpec> movers;  ///< moving objects, not in `mesh`
  std::map<std::string, TrajectorySpec> trajectories;
};

/// Reads a scene file. Relative OBJ paths are taken from the scene file's folder. Throws
/// IoError for an unreadable or malformed file, InvalidArgument for bad values (both naming
/// the object).
Scene loadScene(const std::string& path);

/// The same from JSON text (base_dir: where relative OBJ paths are looked up).
Scene sceneFromJson(const std::string& json_text, const std::string& base_dir = ".");

}  // namespace fragg::sim
