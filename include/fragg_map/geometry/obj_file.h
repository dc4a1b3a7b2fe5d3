// Wavefront OBJ for triangle meshes: each solid is written as its own object ("o solid_N"), and
// each "o" or "g" line of a file read starts a new solid.
#pragma once

#include <string>

#include "fragg_map/geometry/triangle_mesh.h"

namespace fragg::geometry {

/// Writes the mesh atomically (temporary file and rename). Throws IoError.
void writeObj(const TriangleMesh& mesh, const std::string& path);

/// Reads "v" and "f" lines (v, v/vt, v//vn, v/vt/vn and negative indices; polygons are fanned
/// into triangles); other lines are ignored. Throws IoError naming the file and the line.
TriangleMesh readObj(const std::string& path);

}  // namespace fragg::geometry
