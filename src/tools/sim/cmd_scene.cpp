// fragg_map_sim scene SCENE.json -o SCENE.obj: the scene's ground truth as closed meshes.
#include <cstdio>
#include <memory>
#include <string>

#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/sim/scene.h"
#include "sim/commands.h"

namespace fragg::sim::tool {

void addSceneCommand(CLI::App& app) {
  struct Options {
    std::string scene, obj;
  };
  auto o = std::make_shared<Options>();
  CLI::App* c = app.add_subcommand(
      "scene", "Write a scene's ground truth as an OBJ file (one closed solid per object)");
  c->add_option("scene", o->scene, "Scene file (JSON, e.g. config/scenes/campus.json)")->required();
  c->add_option("-o,--output", o->obj, "OBJ file to write")->required();
  c->callback([o] {
    const Scene scene = loadScene(o->scene);
    geometry::writeObj(scene.mesh, o->obj);
    std::printf("%s: %zu triangles, %d solids -> %s\n", scene.name.c_str(), scene.mesh.size(),
                scene.mesh.solid_count, o->obj.c_str());
  });
}

}  // namespace fragg::sim::tool
