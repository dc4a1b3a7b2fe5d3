// Queries on one triangle against analytic values: ray hits and misses (edge tolerance,
// parallel rays), point distance in every Voronoi region, triangle-box overlap.
#include "fragg_map/geometry/triangle_queries.h"

#include <gtest/gtest.h>

#include <cmath>

namespace fragg::geometry {
namespace {

// The right triangle (0,0,0) (2,0,0) (0,2,0) in the plane z = 0.
const Eigen::Vector3f kV0(0, 0, 0), kE1(2, 0, 0), kE2(0, 2, 0);

float down(float x, float y, float edge_eps = 0.f) {
  return rayTriangle({x, y, 3.f}, {0, 0, -1}, kV0, kE1, kE2, edge_eps);
}

TEST(GeometryTriangle, RayTriangleHitsAtTheAnalyticDistance) {
  EXPECT_FLOAT_EQ(down(0.5f, 0.5f), 3.f);
  // Slanted: from (0.5, 0.5, 1) along (1, 1, -1)/sqrt3 meets z = 0 at (1.5, 1.5): outside the
  // hypotenuse x + y = 2. Along (0.25, 0.25, -1) it meets it at (0.75, 0.75), inside.
  const Eigen::Vector3f o(0.5f, 0.5f, 1.f);
  EXPECT_LT(rayTriangle(o, Eigen::Vector3f(1, 1, -1).normalized(), kV0, kE1, kE2), 0.f);
  const Eigen::Vector3f d = Eigen::Vector3f(0.25f, 0.25f, -1).normalized();
  EXPECT_NEAR(rayTriangle(o, d, kV0, kE1, kE2), Eigen::Vector3f(0.25f, 0.25f, -1).norm(), 1e-6f);
  // Either face: the triangle is hit from below too.
  EXPECT_FLOAT_EQ(rayTriangle({0.5f, 0.5f, -2.f}, {0, 0, 1}, kV0, kE1, kE2), 2.f);
  // The line's hit behind the origin comes back as a negative t.
  EXPECT_FLOAT_EQ(rayTriangle({0.5f, 0.5f, -2.f}, {0, 0, -1}, kV0, kE1, kE2), -2.f);
}

TEST(GeometryTriangle, RayTriangleMissesOutsideAndParallel) {
  EXPECT_LT(down(-0.1f, 0.5f), 0.f);  // beyond the edge x = 0
  EXPECT_LT(down(0.5f, -0.1f), 0.f);  // beyond y = 0
  EXPECT_LT(down(1.1f, 1.f), 0.f);    // beyond x + y = 2
  EXPECT_LT(rayTriangle({0.5f, 0.5f, 0.f}, {1, 0, 0}, kV0, kE1, kE2), 0.f);  // in the plane
  EXPECT_LT(rayTriangle({0.5f, 0.5f, 1.f}, {0, 1, 0}, kV0, kE1, kE2), 0.f);  // parallel
}

TEST(GeometryTriangle, EdgeToleranceWidensTheBarycentricLimits) {
  // 1e-6 outside the edge x = 0 (u = -5e-7 for an edge of 2): a miss without tolerance, a hit
  // with 1e-5, and still a miss 1e-4 outside.
  EXPECT_LT(down(-1e-6f, 0.5f), 0.f);
  EXPECT_FLOAT_EQ(down(-1e-6f, 0.5f, 1e-5f), 3.f);
  EXPECT_LT(down(-1e-4f, 0.5f, 1e-5f), 0.f);
}

TEST(GeometryTriangle, PointDistanceInEveryVoronoiRegion) {
  const Eigen::Vector3f a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  auto d = [&](float x, float y, float z) {
    return std::sqrt(pointTriangleDistanceSq({x, y, z}, a, b, c));
  };
  EXPECT_FLOAT_EQ(d(0.5f, 0.5f, 1.5f), 1.5f);     // face
  EXPECT_FLOAT_EQ(d(0.5f, 0.5f, -0.25f), 0.25f);  // face, other side
  EXPECT_FLOAT_EQ(d(-1, -1, 0), std::sqrt(2.f));  // vertex a
  EXPECT_FLOAT_EQ(d(3, -1, 1), std::sqrt(3.f));   // vertex b
  EXPECT_FLOAT_EQ(d(-1, 4, 0), std::sqrt(5.f));   // vertex c
  EXPECT_FLOAT_EQ(d(1, -2, 0), 2.f);              // edge ab
  EXPECT_FLOAT_EQ(d(-3, 1, 4), 5.f);              // edge ca
  EXPECT_FLOAT_EQ(d(2, 2, 0), std::sqrt(2.f));    // edge bc (x + y = 2)
  EXPECT_FLOAT_EQ(d(1, 1, 0), 0.f);               // on the edge bc
  EXPECT_FLOAT_EQ(pointTriangleDistanceSq(b, a, b, c), 0.f);
}

TEST(GeometryTriangle, TriangleBoxOverlap) {
  const Eigen::Vector3d c(0, 0, 0), h(0.5, 0.5, 0.5);
  // A large triangle in the plane z = 0.4 covers the box; z = 0.6 misses it.
  EXPECT_TRUE(triangleBoxOverlap(c, h, {-5, -5, 0.4}, {5, -5, 0.4}, {0, 5, 0.4}));
  EXPECT_FALSE(triangleBoxOverlap(c, h, {-5, -5, 0.6}, {5, -5, 0.6}, {0, 5, 0.6}));
  // A tilted one passing near the corner: x + y + z = 1.6 misses (corner sum 1.5), 1.4 hits.
  auto tilted = [&](double s) { return triangleBoxOverlap(c, h, {s, 0, 0}, {0, s, 0}, {0, 0, s}); };
  EXPECT_TRUE(tilted(1.4));
  EXPECT_FALSE(tilted(1.6));
  // A vertical triangle beside a box edge.
  EXPECT_FALSE(triangleBoxOverlap(c, h, {0.9, -0.9, -2}, {0.9, -0.9, 2}, {2, 0.2, 0}));
  // Touching counts: a triangle lying in the face x = 0.5; a small one wholly inside the box.
  EXPECT_TRUE(triangleBoxOverlap(c, h, {0.5, -1, -1}, {0.5, 1, -1}, {0.5, 0, 1}));
  EXPECT_TRUE(triangleBoxOverlap(c, h, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}));
  // The box centre and half extents are honoured: the same triangle against a moved box.
  EXPECT_FALSE(triangleBoxOverlap({10, 0, 0}, h, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}));
  EXPECT_TRUE(triangleBoxOverlap({10, 0, 0}, {10, 1, 1}, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}));
}

}  // namespace
}  // namespace fragg::geometry
