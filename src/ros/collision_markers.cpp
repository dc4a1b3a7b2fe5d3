// Markers of a collision check: one shape per drawn pose, red or green.
#include "fragg_map/ros/collision_markers.h"

#include "fragg_map/errors.h"
#include "point_msg.h"

namespace fragg::ros {
namespace {

using visualization_msgs::Marker;

geometry_msgs::Pose toPose(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose pose;
  pose.position = toPoint(T.translation());
  const Eigen::Quaterniond q(T.rotation());
  pose.orientation.x = q.x();
  pose.orientation.y = q.y();
  pose.orientation.z = q.z();
  pose.orientation.w = q.w();
  return pose;
}

void setColor(Marker& m, bool colliding) {
  m.color.r = colliding ? 1.0f : 0.1f;
  m.color.g = colliding ? 0.1f : 0.9f;
  m.color.b = 0.1f;
  m.color.a = colliding ? 0.8f : 0.2f;
}

// The marker(s) of `shape` at T_map_shape, appended to `out`.
void addShape(const planning::CollisionShape& shape, const Eigen::Isometry3d& T_map_shape,
              Marker base, int* id, visualization_msgs::MarkerArray* out) {
  base.pose = toPose(T_map_shape);
  auto push = [&](Marker m) {
    m.id = (*id)++;
    out->markers.push_back(std::move(m));
  };
  switch (shape.kind()) {
    case planning::ShapeKind::kBox: {
      base.type = Marker::CUBE;
      base.scale.x = 2.0 * shape.halfExtents().x();
      base.scale.y = 2.0 * shape.halfExtents().y();
      base.scale.z = 2.0 * shape.halfExtents().z();
      push(base);
      break;
    }
    case planning::ShapeKind::kSphere: {
      base.type = Marker::SPHERE;
      base.scale.x = base.scale.y = base.scale.z = 2.0 * shape.radius();
      push(base);
      break;
    }
    case planning::ShapeKind::kCapsule: {
      const double d = 2.0 * shape.radius();
      Marker body = base;
      body.type = Marker::CYLINDER;
      body.scale.x = body.scale.y = d;
      body.scale.z = shape.length();
      if (shape.length() > 0.0) push(body);
      for (double side : {-0.5, 0.5}) {
        Marker cap = base;
        cap.type = Marker::SPHERE;
        cap.scale.x = cap.scale.y = cap.scale.z = d;
        cap.pose = toPose(T_map_shape * Eigen::Translation3d(0, 0, side * shape.length()));
        push(cap);
      }
      break;
    }
    case planning::ShapeKind::kMesh: {
      base.type = Marker::TRIANGLE_LIST;
      base.scale.x = base.scale.y = base.scale.z = 1.0;
      const geometry::TriangleMesh& mesh = shape.meshBvh()->mesh();
      base.points.reserve(3 * mesh.size());
      for (const Eigen::Vector3i& tri : mesh.triangles)
        for (int k = 0; k < 3; ++k)
          base.points.push_back(toPoint(mesh.vertices_m[tri[k]].cast<double>()));
      push(base);
      break;
    }
  }
}

}  // namespace

visualization_msgs::MarkerArray collisionMarkers(const CollisionMarkerInput& in,
                                                 const std::string& frame_id,
                                                 const ::ros::Time& stamp, size_t max_poses) {
  if (!in.shape || !in.T_map_shape || !in.collides || in.T_map_shape->size() != in.collides->size())
    throw fragg::InvalidArgument("collision markers: one flag per pose is needed");
  visualization_msgs::MarkerArray out;
  Marker base;
  base.header.frame_id = frame_id;
  base.header.stamp = stamp;
  base.action = Marker::DELETEALL;
  out.markers.push_back(base);
  base.action = Marker::ADD;
  base.pose.orientation.w = 1.0;

  const std::vector<Eigen::Isometry3d>& poses = *in.T_map_shape;
  const std::vector<bool>& collides = *in.collides;
  size_t drawn = 0;
  int colliding_id = 0, free_id = 0;
  for (bool colliding : {true, false}) {
    for (size_t i = 0; i < poses.size() && drawn < max_poses; ++i) {
      if (collides[i] != colliding) continue;
      Marker m = base;
      m.ns = colliding ? "colliding" : "free";
      setColor(m, colliding);
      addShape(*in.shape, poses[i], m, colliding ? &colliding_id : &free_id, &out);
      ++drawn;
    }
  }
  if (in.path_mode && poses.size() > 1) {
    Marker line = base;
    line.ns = "path";
    line.id = 0;
    line.type = Marker::LINE_STRIP;
    line.scale.x = 0.02;  // line width [m]
    line.color.r = line.color.g = line.color.b = 0.9f;
    line.color.a = 1.0f;
    for (const Eigen::Isometry3d& T : poses) line.points.push_back(toPoint(T.translation()));
    out.markers.push_back(std::move(line));
  }
  if (in.path_mode && in.T_map_path_hit) {
    Marker hit = base;
    hit.ns = "path_hit";
    setColor(hit, true);
    hit.color.a = 1.0f;
    int id = 0;
    addShape(*in.shape, *in.T_map_path_hit, hit, &id, &out);
  }
  return out;
}

}  // namespace fragg::ros
