// Wavefront OBJ meshes (simulator scenes, `fragg_map collide --mesh`, the server's robot mesh).
#include "fragg_map/errors.h"
#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/planning/collision_shape.h"
#include "fuzz_targets.h"
#include "fuzz_util.h"

namespace fragg::fuzz {

bool obj(const uint8_t* data, size_t size) {
  const std::string path = writeInputFile(data, size, ".obj");
  try {
    const geometry::TriangleMesh mesh = geometry::readObj(path);
    // As `collide --mesh` and the server's robot mesh use it: the mesh's BVH is built.
    planning::CollisionShape::mesh(mesh, 1.0);
    return true;
  } catch (const IoError&) {
  } catch (const InvalidArgument&) {
  }
  return false;
}

}  // namespace fragg::fuzz
