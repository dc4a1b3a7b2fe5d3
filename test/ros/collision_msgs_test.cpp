// ~check_collision's message rules: shapes from a type and dimensions (refusals included),
// shape_msgs/Mesh -> triangle mesh (closed or not, bad indices), the request's shape choice
// (its own mesh, the configured one, neither), and the `collisions` markers (one shape per
// drawn pose, colliding ones first and red, the cap, path line and hit).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/ros/collision_markers.h"
#include "fragg_map/ros/collision_shape_msg.h"

namespace {

using fragg::planning::CollisionShape;
using fragg::planning::ShapeKind;
using visualization_msgs::Marker;

shape_msgs::Mesh cubeMsg(double edge_m) {
  shape_msgs::Mesh m;
  for (int i = 0; i < 8; ++i) {
    geometry_msgs::Point p;
    p.x = (i & 1 ? 0.5 : -0.5) * edge_m;
    p.y = (i & 2 ? 0.5 : -0.5) * edge_m;
    p.z = (i & 4 ? 0.5 : -0.5) * edge_m;
    m.vertices.push_back(p);
  }
  // Two triangles per face, counter-clockwise from outside.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    shape_msgs::MeshTriangle a, b;
    a.vertex_indices = {static_cast<uint32_t>(f[0]), static_cast<uint32_t>(f[1]),
                        static_cast<uint32_t>(f[2])};
    b.vertex_indices = {static_cast<uint32_t>(f[0]), static_cast<uint32_t>(f[2]),
                        static_cast<uint32_t>(f[3])};
    m.triangles.push_back(a);
    m.triangles.push_back(b);
  }
  return m;
}

TEST(CollisionShapeMsg, TypesAndDimensions) {
  const CollisionShape box = fragg::ros::shapeFromDimensions("box", {0.4, 0.6, 1.0});
  EXPECT_EQ(box.kind(), ShapeKind::kBox);
  EXPECT_TRUE(box.halfExtents().isApprox(Eigen::Vector3d(0.2, 0.3, 0.5)));
  const CollisionShape sphere = fragg::ros::shapeFromDimensions("sphere", {0.25});
  EXPECT_EQ(sphere.kind(), ShapeKind::kSphere);
  EXPECT_EQ(sphere.radius(), 0.25);
  const CollisionShape capsule = fragg::ros::shapeFromDimensions("capsule", {0.2, 1.0});
  EXPECT_EQ(capsule.kind(), ShapeKind::kCapsule);
  EXPECT_EQ(capsule.radius(), 0.2);
  EXPECT_EQ(capsule.length(), 1.0);
}

TEST(CollisionShapeMsg, BadShapesAreRefused) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [type, dims] :
       std::vector<std::pair<std::string, std::vector<double>>>{{"cube", {1, 1, 1}},
                                                                {"", {}},
                                                                {"box", {1, 1}},
                                                                {"box", {1, 0, 1}},
                                                                {"box", {1, -1, 1}},
                                                                {"box", {1, nan, 1}},
                                                                {"sphere", {}},
                                                                {"sphere", {0.0}},
                                                                {"sphere", {1.0, 2.0}},
                                                                {"capsule", {0.2}},
                                                                {"capsule", {0.0, 1.0}},
                                                                {"capsule", {0.2, -1.0}}})
    EXPECT_THROW(fragg::ros::shapeFromDimensions(type, dims), fragg::InvalidArgument)
        << type << " with " << dims.size() << " dimensions";
}

TEST(CollisionShapeMsg, MeshFromMessage) {
  const fragg::geometry::TriangleMesh mesh = fragg::ros::meshFromMsg(cubeMsg(1.0));
  EXPECT_EQ(mesh.size(), 12u);
  EXPECT_EQ(mesh.solid_count, 1);
  const CollisionShape shape = CollisionShape::mesh(mesh);
  EXPECT_TRUE(shape.meshClosed());
  EXPECT_NEAR(shape.boundingRadius(), std::sqrt(0.75), 1e-6);

  shape_msgs::Mesh bad_index = cubeMsg(1.0);
  bad_index.triangles[3].vertex_indices[1] = 8;
  EXPECT_THROW(fragg::ros::meshFromMsg(bad_index), fragg::InvalidArgument);
  shape_msgs::Mesh nan_vertex = cubeMsg(1.0);
  nan_vertex.vertices[2].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(fragg::ros::meshFromMsg(nan_vertex), fragg::InvalidArgument);
  EXPECT_TRUE(fragg::ros::meshFromMsg(shape_msgs::Mesh()).empty());
}

TEST(CollisionShapeMsg, RequestMeshConfiguredMeshOrNeither) {
  const std::optional<CollisionShape> none;
  const CollisionShape own = fragg::ros::shapeFromRequest("mesh", {}, cubeMsg(2.0), none);
  EXPECT_EQ(own.kind(), ShapeKind::kMesh);
  EXPECT_NEAR(own.boundingRadius(), std::sqrt(3.0), 1e-6);
  const std::optional<CollisionShape> configured =
      CollisionShape::mesh(fragg::ros::meshFromMsg(cubeMsg(0.5)));
  // The request's triangles win over the configured mesh; without them the configured one.
  EXPECT_NEAR(fragg::ros::shapeFromRequest("mesh", {}, cubeMsg(2.0), configured).boundingRadius(),
              std::sqrt(3.0), 1e-6);
  EXPECT_NEAR(
      fragg::ros::shapeFromRequest("mesh", {}, shape_msgs::Mesh(), configured).boundingRadius(),
      std::sqrt(3.0) / 4, 1e-6);
  EXPECT_THROW(fragg::ros::shapeFromRequest("mesh", {}, shape_msgs::Mesh(), none),
               fragg::InvalidArgument);
  EXPECT_THROW(fragg::ros::shapeFromRequest("mesh", {1.0}, cubeMsg(1.0), none),
               fragg::InvalidArgument);
  // Every vertex on one line: no triangle has an area.
  shape_msgs::Mesh flat = cubeMsg(1.0);
  for (geometry_msgs::Point& p : flat.vertices) p.y = p.z = 0.0;
  EXPECT_THROW(fragg::ros::shapeFromRequest("mesh", {}, flat, none), fragg::InvalidArgument);
  // Other types ignore the mesh field.
  EXPECT_EQ(fragg::ros::shapeFromRequest("sphere", {0.5}, cubeMsg(1.0), none).kind(),
            ShapeKind::kSphere);
}

Eigen::Isometry3d at(double x, double y, double z) {
  return Eigen::Isometry3d(Eigen::Translation3d(x, y, z));
}

std::map<std::string, std::vector<const Marker*>> byNamespace(
    const visualization_msgs::MarkerArray& a) {
  std::map<std::string, std::vector<const Marker*>> out;
  for (const Marker& m : a.markers)
    if (m.action == Marker::ADD) out[m.ns].push_back(&m);
  return out;
}

TEST(CollisionMarkers, ColliderRedFreeGreenCapAndPath) {
  const CollisionShape box = fragg::ros::shapeFromDimensions("box", {0.4, 0.6, 1.0});
  const std::vector<Eigen::Isometry3d> poses = {at(0, 0, 0), at(1, 0, 0), at(2, 0, 0), at(3, 0, 0)};
  const std::vector<bool> collides = {false, true, false, true};
  fragg::ros::CollisionMarkerInput in;
  in.shape = &box;
  in.T_map_shape = &poses;
  in.collides = &collides;
  const auto all = fragg::ros::collisionMarkers(in, "map", ros::Time(5.0), 10);
  ASSERT_FALSE(all.markers.empty());
  EXPECT_EQ(all.markers[0].action, Marker::DELETEALL);
  auto ns = byNamespace(all);
  ASSERT_EQ(ns["colliding"].size(), 2u);
  ASSERT_EQ(ns["free"].size(), 2u);
  EXPECT_EQ(ns.count("path"), 0u);
  EXPECT_EQ(ns["colliding"][0]->pose.position.x, 1.0);
  EXPECT_EQ(ns["colliding"][1]->pose.position.x, 3.0);
  for (const Marker* m : ns["colliding"]) {
    EXPECT_EQ(m->type, Marker::CUBE);
    EXPECT_EQ(m->header.frame_id, "map");
    EXPECT_DOUBLE_EQ(m->scale.y, 0.6);
    EXPECT_GT(m->color.r, 0.9f);
    EXPECT_LT(m->color.g, 0.2f);
  }
  for (const Marker* m : ns["free"]) {
    EXPECT_GT(m->color.g, 0.8f);
    EXPECT_LT(m->color.a, ns["colliding"][0]->color.a);
  }
  // The cap keeps the colliding poses first.
  const auto capped = byNamespace(fragg::ros::collisionMarkers(in, "map", ros::Time(), 3));
  EXPECT_EQ(capped.at("colliding").size(), 2u);
  EXPECT_EQ(capped.at("free").size(), 1u);

  in.path_mode = true;
  in.T_map_path_hit = at(0.5, 0, 0);
  auto path = byNamespace(fragg::ros::collisionMarkers(in, "map", ros::Time(), 10));
  ASSERT_EQ(path["path"].size(), 1u);
  EXPECT_EQ(path["path"][0]->type, Marker::LINE_STRIP);
  EXPECT_EQ(path["path"][0]->points.size(), 4u);
  ASSERT_EQ(path["path_hit"].size(), 1u);
  EXPECT_EQ(path["path_hit"][0]->pose.position.x, 0.5);

  const std::vector<bool> short_flags = {true};
  in.collides = &short_flags;
  EXPECT_THROW(fragg::ros::collisionMarkers(in, "map", ros::Time(), 10), fragg::InvalidArgument);
}

TEST(CollisionMarkers, CapsuleAndMeshShapes) {
  const std::vector<Eigen::Isometry3d> poses = {at(1, 2, 3)};
  const std::vector<bool> collides = {true};
  fragg::ros::CollisionMarkerInput in;
  in.T_map_shape = &poses;
  in.collides = &collides;
  const CollisionShape capsule = fragg::ros::shapeFromDimensions("capsule", {0.2, 1.0});
  in.shape = &capsule;
  auto c = byNamespace(fragg::ros::collisionMarkers(in, "map", ros::Time(), 10));
  ASSERT_EQ(c["colliding"].size(), 3u);  // cylinder and two caps
  EXPECT_EQ(c["colliding"][0]->type, Marker::CYLINDER);
  EXPECT_DOUBLE_EQ(c["colliding"][0]->scale.z, 1.0);
  EXPECT_DOUBLE_EQ(c["colliding"][1]->pose.position.z, 2.5);
  EXPECT_DOUBLE_EQ(c["colliding"][2]->pose.position.z, 3.5);
  const CollisionShape mesh = CollisionShape::mesh(fragg::ros::meshFromMsg(cubeMsg(1.0)), 2.0);
  in.shape = &mesh;
  auto m = byNamespace(fragg::ros::collisionMarkers(in, "map", ros::Time(), 10));
  ASSERT_EQ(m["colliding"].size(), 1u);
  EXPECT_EQ(m["colliding"][0]->type, Marker::TRIANGLE_LIST);
  ASSERT_EQ(m["colliding"][0]->points.size(), 36u);
  double max_x = 0.0;
  for (const auto& p : m["colliding"][0]->points) max_x = std::max(max_x, p.x);
  EXPECT_DOUBLE_EQ(max_x, 1.0);  // scaled by 2, in the shape frame
}

}  // namespace
