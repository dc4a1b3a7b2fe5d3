// Tiled scenes (private to src/sim): a scene file's "tile" section lays the objects of another
// scene file out on a grid, so that a long drive (W4) runs through a large deterministic world
// built from the campus of W1 without a copy of its objects.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace fragg::sim {

/// Expands `"tile": {"scene": FILE, "count": [nx, ny], "step": [dx, dy]}` of scene JSON `j`
/// (FILE relative to base_dir): the objects of FILE are repeated nx * ny times, shifted by
/// (i dx, j dy) in the xy plane before they are placed on the ground, and come before `j`'s own
/// objects. Without a "ground" in `j`, FILE's ground is taken with its extent grown to cover
/// every tile. FILE's trajectories are not taken, nor may FILE tile itself. Relative OBJ paths
/// of FILE's meshes are made relative to FILE's folder. Returns `j` without "tile" (unchanged
/// when it has none). Throws IoError (FILE unreadable or not JSON) or InvalidArgument (bad
/// count, step or object coordinates).
nlohmann::json expandSceneTiles(const nlohmann::json& j, const std::string& base_dir);

}  // namespace fragg::sim
