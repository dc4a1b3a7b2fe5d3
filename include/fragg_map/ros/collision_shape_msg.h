// The shape of a ~check_collision request as a fragg::planning::CollisionShape: a type name
// with its dimensions, or a shape_msgs/Mesh. ROS-free rules apart from the message types; the
// core checks the values (CollisionShape::box/sphere/capsule/mesh).
#pragma once

#include <shape_msgs/Mesh.h>

#include <optional>
#include <string>
#include <vector>

#include "fragg_map/geometry/triangle_mesh.h"
#include "fragg_map/planning/collision_shape.h"

namespace fragg::ros {

/// "box" (full lengths LX LY LZ), "sphere" (R) or "capsule" (R L), metres. Throws
/// fragg::InvalidArgument naming the shape for an unknown type, a wrong number of dimensions
/// or a dimension the core refuses (zero, negative, non-finite).
planning::CollisionShape shapeFromDimensions(const std::string& type,
                                             const std::vector<double>& dimensions_m);

/// The message's triangles as one solid (metres). Throws fragg::InvalidArgument for a vertex
/// index out of range or a non-finite vertex; an empty message gives an empty mesh.
geometry::TriangleMesh meshFromMsg(const shape_msgs::Mesh& msg);

/// The request's shape: shapeFromDimensions, or for "mesh" the request's mesh when it has
/// triangles, else `configured_mesh` (the collision/mesh parameter's). Throws
/// fragg::InvalidArgument for a degenerate mesh, or "mesh" with neither.
planning::CollisionShape shapeFromRequest(
    const std::string& type, const std::vector<double>& dimensions_m, const shape_msgs::Mesh& mesh,
    const std::optional<planning::CollisionShape>& configured_mesh);

}  // namespace fragg::ros
