#include "scene_tiles.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "fragg_map/errors.h"

namespace fragg::sim {
namespace {

using nlohmann::json;

constexpr int kMaxTiles = 10000;

// Adds (dx, dy) to the numbers at `offsets` of the array o[key] (absent keys are left alone:
// the object's own reader reports them).
void shiftArray(json& o, const char* key, std::initializer_list<std::pair<int, double>> offsets) {
  if (!o.contains(key) || !o.at(key).is_array()) return;
  json& a = o.at(key);
  for (const auto& [index, delta] : offsets)
    if (index < int(a.size()) && a[index].is_number()) a[index] = a[index].get<double>() + delta;
}

json shiftObject(json o, double dx, double dy, const std::string& tile_dir) {
  const std::string type = o.value("type", "");
  if (type == "box") {
    shiftArray(o, "min", {{0, dx}, {1, dy}});
    shiftArray(o, "max", {{0, dx}, {1, dy}});
  } else if (type == "building") {
    shiftArray(o, "footprint", {{0, dx}, {1, dy}, {2, dx}, {3, dy}});
  } else if (type == "wall" || type == "cylinder" || type == "pipe") {
    shiftArray(o, "from", {{0, dx}, {1, dy}});
    shiftArray(o, "to", {{0, dx}, {1, dy}});
  } else if (type == "tree") {
    shiftArray(o, "at", {{0, dx}, {1, dy}});
  } else if (type == "sphere") {
    shiftArray(o, "centre", {{0, dx}, {1, dy}});
  } else if (type == "mesh") {
    if (!o.contains("offset")) o["offset"] = json::array({0.0, 0.0, 0.0});
    shiftArray(o, "offset", {{0, dx}, {1, dy}});
    if (o.contains("obj") && o.at("obj").is_string()) {
      const std::string path = o.at("obj").get<std::string>();
      if (!path.empty() && path[0] != '/') o["obj"] = tile_dir + "/" + path;
    }
  }
  return o;  // unknown types: the object reader names them
}

std::pair<double, double> pairOf(const json& t, const char* key) {
  if (!t.contains(key) || !t.at(key).is_array() || t.at(key).size() != 2 ||
      !t.at(key)[0].is_number() || !t.at(key)[1].is_number())
    throw InvalidArgument(std::string("tile: '") + key + "' must be an array of two numbers");
  return {t.at(key)[0].get<double>(), t.at(key)[1].get<double>()};
}

json readTileScene(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("tile: " + path + ": cannot open scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    return json::parse(ss.str());
  } catch (const json::exception& e) {
    throw IoError("tile: " + path + ": not valid JSON: " + e.what());
  }
}

}  // namespace

json expandSceneTiles(const json& j, const std::string& base_dir) {
  if (!j.contains("tile")) return j;
  const json& t = j.at("tile");
  if (!t.is_object() || !t.contains("scene") || !t.at("scene").is_string())
    throw InvalidArgument("tile: 'scene' must name a scene file");
  const auto [count_x, count_y] = pairOf(t, "count");
  const auto [step_x_m, step_y_m] = pairOf(t, "step");
  if (!(count_x >= 1 && count_y >= 1 && count_x * count_y <= kMaxTiles &&
        count_x == std::floor(count_x) && count_y == std::floor(count_y)))
    throw InvalidArgument("tile: 'count' must be two whole numbers >= 1 (at most " +
                          std::to_string(kMaxTiles) + " tiles)");
  std::string path = t.at("scene").get<std::string>();
  if (!path.empty() && path[0] != '/') path = base_dir + "/" + path;
  const size_t slash = path.find_last_of('/');
  const std::string tile_dir = slash == std::string::npos ? "." : path.substr(0, slash);
  const json tile = readTileScene(path);
  if (tile.contains("tile")) throw InvalidArgument("tile: " + path + " tiles itself (not nested)");

  json out = j;
  out.erase("tile");
  json objects = json::array();
  if (tile.contains("objects")) {
    if (!tile.at("objects").is_array())
      throw InvalidArgument("tile: " + path + ": 'objects' must be an array");
    for (int iy = 0; iy < int(count_y); ++iy)
      for (int ix = 0; ix < int(count_x); ++ix)
        for (const json& o : tile.at("objects"))
          objects.push_back(shiftObject(o, ix * step_x_m, iy * step_y_m, tile_dir));
  }
  if (j.contains("objects")) {
    if (!j.at("objects").is_array()) throw InvalidArgument("'objects' must be an array");
    for (const json& o : j.at("objects")) objects.push_back(o);
  }
  out["objects"] = std::move(objects);
  if (!j.contains("ground") && tile.contains("ground")) {
    json ground = tile.at("ground");
    if (ground.contains("extent") && ground.at("extent").is_array() &&
        ground.at("extent").size() == 4) {
      // Grow towards the tiles: [x0 y0 x1 y1] covers tile (0, 0) up to tile (nx-1, ny-1).
      const double dx = (count_x - 1) * step_x_m, dy = (count_y - 1) * step_y_m;
      shiftArray(ground, "extent", {{dx < 0 ? 0 : 2, dx}, {dy < 0 ? 1 : 3, dy}});
    }
    out["ground"] = std::move(ground);
  }
  return out;
}

}  // namespace fragg::sim
