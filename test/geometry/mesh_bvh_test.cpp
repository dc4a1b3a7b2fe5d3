// The mesh BVH: analytic ray hits and distances on boxes, inside tests per solid, and nearest
// hits, distances and "within r" against brute force over every triangle (SAH and median
// splits), empty and malformed meshes.
#include "fragg_map/geometry/mesh_bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "fragg_map/errors.h"
#include "mesh_test_util.h"

namespace fragg::geometry {
namespace {

using test::boxSolid;

float hitDistance(const MeshBvh& bvh, Eigen::Vector3f o, Eigen::Vector3f d) {
  RayHit hit;
  if (!bvh.intersect(o, d.normalized(), 1000.f, &hit)) return -1.f;
  return hit.t_m;
}

// The brute-force answers, with each triangle as the BVH stores it (v0, v1 - v0, v2 - v0), so
// that the two must agree bit for bit.
struct Tri {
  Eigen::Vector3f v0, e1, e2;
};
std::vector<Tri> trianglesOf(const TriangleMesh& m) {
  std::vector<Tri> out;
  for (const Eigen::Vector3i& t : m.triangles) {
    const Eigen::Vector3f& a = m.vertices_m[t[0]];
    out.push_back({a, m.vertices_m[t[1]] - a, m.vertices_m[t[2]] - a});
  }
  return out;
}
RayHit bruteNearest(const std::vector<Tri>& tris, const Eigen::Vector3f& o,
                    const Eigen::Vector3f& d, float t_max) {
  RayHit best{t_max, -1};
  for (size_t i = 0; i < tris.size(); ++i) {
    const float t = rayTriangle(o, d, tris[i].v0, tris[i].e1, tris[i].e2);
    if (t > 0.f && t < best.t_m) best = {t, static_cast<int32_t>(i)};
  }
  return best;
}
float bruteDistanceSq(const std::vector<Tri>& tris, const Eigen::Vector3f& p) {
  float best = INFINITY;
  for (const Tri& t : tris)
    best = std::min(best, pointTriangleDistanceSq(p, t.v0, t.v0 + t.e1, t.v0 + t.e2));
  return best;
}

// Rays from random origins towards random targets, checked against brute force: the same
// distance (and a triangle hit there), or no hit on both sides. Returns the number of hits.
int expectNearestHitsMatchBruteForce(const TriangleMesh& m, float origin_half_m,
                                     float target_half_m, int rays, uint32_t seed) {
  const MeshBvh bvh(m);
  const std::vector<Tri> tris = trianglesOf(m);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> origin(-origin_half_m, origin_half_m),
      target(-target_half_m, target_half_m);
  int hits = 0, ties = 0;
  for (int i = 0; i < rays; ++i) {
    const Eigen::Vector3f o(origin(rng), origin(rng), origin(rng));
    const Eigen::Vector3f d =
        (Eigen::Vector3f(target(rng), target(rng), target(rng)) - o).normalized();
    const float t_max = 3.f * origin_half_m;
    const RayHit expected = bruteNearest(tris, o, d, t_max);
    RayHit hit;
    const bool found = bvh.intersect(o, d, t_max, &hit);
    EXPECT_EQ(found, expected.triangle >= 0) << "ray " << i;
    if (!found || expected.triangle < 0) continue;
    ++hits;
    // The nearest distance, and a triangle really hit there (where triangles meet, several
    // can be hit at the very same t: any of them will do).
    EXPECT_EQ(hit.t_m, expected.t_m) << "ray " << i;
    if (hit.triangle < 0 || hit.triangle >= static_cast<int32_t>(tris.size())) {
      ADD_FAILURE() << "ray " << i << ": triangle " << hit.triangle << " does not exist";
      continue;
    }
    const Tri& t = tris[hit.triangle];
    EXPECT_EQ(rayTriangle(o, d, t.v0, t.e1, t.e2), hit.t_m) << "ray " << i;
    ties += hit.triangle != expected.triangle;
  }
  EXPECT_LT(ties, hits / 10);  // ties are the exception
  return hits;
}

TEST(GeometryMeshBvh, RayHitsBoxFacesAtTheAnalyticDistance) {
  const MeshBvh bvh(boxSolid({-1, -2, -3}, {1, 2, 3}));
  EXPECT_NEAR(hitDistance(bvh, {-5, 0.3f, 0.7f}, {1, 0, 0}), 4.f, 1e-5f);
  EXPECT_NEAR(hitDistance(bvh, {0.2f, 7, -0.4f}, {0, -1, 0}), 5.f, 1e-5f);
  EXPECT_NEAR(hitDistance(bvh, {0.1f, 0.2f, 10}, {0, 0, -1}), 7.f, 1e-5f);
  // Oblique: from (-5, 0, 0) towards +x+z at 45 degrees enters the x = -1 face at z = 4 > 3:
  // it crosses the top face z = 3 instead, at x = -2 (outside): a miss.
  EXPECT_LT(hitDistance(bvh, {-5, 0, 0}, {1, 0, 1}), 0.f);
  EXPECT_NEAR(hitDistance(bvh, {-3, 0, 0}, {1, 0, 1}), 2.f * std::sqrt(2.f), 1e-5f);
  // From inside, the first face ahead.
  EXPECT_NEAR(hitDistance(bvh, {0, 0, 0}, {0, 0, 1}), 3.f, 1e-5f);
  // t_max is exclusive of farther hits: the face at 4 m is not found within 3.9 m.
  RayHit hit;
  EXPECT_FALSE(bvh.intersect({-5, 0.3f, 0.7f}, {1, 0, 0}, 3.9f, &hit));
  EXPECT_TRUE(bvh.intersect({-5, 0.3f, 0.7f}, {1, 0, 0}, 4.1f, nullptr));
  // Behind the origin does not count.
  EXPECT_LT(hitDistance(bvh, {-5, 0.3f, 0.7f}, {-1, 0, 0}), 0.f);
}

TEST(GeometryMeshBvh, RaysThroughTheEdgeSharedByTwoTrianglesHitOneOfThem) {
  // Every face of the box is split along a diagonal; the top face's diagonal runs from
  // (0, 0, 1) to (1, 1, 1). Rays straight down onto it must not slip through the crack.
  const MeshBvh bvh(boxSolid({0, 0, 0}, {1, 1, 1}));
  for (int i = 1; i < 100; ++i) {
    const float s = i / 100.f;
    RayHit hit;
    ASSERT_TRUE(bvh.intersect({s, s, 5.f}, {0, 0, -1}, 100.f, &hit)) << s;
    EXPECT_NEAR(hit.t_m, 4.f, 1e-5f);
  }
}

TEST(GeometryMeshBvh, DistanceAndInsidePerSolidEvenWhereSolidsOverlap) {
  TriangleMesh m;
  m.appendSolid(boxSolid({0, 0, 0}, {2, 2, 2}));
  m.appendSolid(boxSolid({1, 1, 1}, {3, 3, 3}));  // overlaps the first
  const MeshBvh bvh(m);
  EXPECT_TRUE(bvh.inside({0.5f, 0.5f, 0.5f}));
  EXPECT_TRUE(bvh.inside({1.5f, 1.5f, 1.5f}));  // inside both
  EXPECT_TRUE(bvh.inside({2.5f, 2.5f, 2.5f}));
  EXPECT_FALSE(bvh.inside({2.5f, 0.5f, 0.5f}));
  EXPECT_FALSE(bvh.inside({-0.5f, 1.0f, 1.0f}));
  EXPECT_NEAR(bvh.distance({-0.5f, 1.0f, 1.0f}, 10.f), 0.5f, 1e-6f);
  EXPECT_NEAR(bvh.distance({4.f, 4.f, 3.f}, 10.f), std::sqrt(2.f), 1e-6f);
  EXPECT_FLOAT_EQ(bvh.distance({40.f, 0.f, 0.f}, 5.f), 5.f);
  EXPECT_TRUE(bvh.withinDistance({-0.5f, 1.0f, 1.0f}, 0.51f));
  EXPECT_FALSE(bvh.withinDistance({-0.5f, 1.0f, 1.0f}, 0.49f));
}

TEST(GeometryMeshBvh, InsideAgreesWithTheBoxesAtRandomPoints) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> corner(-5.f, 5.f), size(1.f, 4.f), point(-6.f, 6.f);
  std::vector<Eigen::AlignedBox3f> boxes;
  TriangleMesh m;
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector3f lo(corner(rng), corner(rng), corner(rng));
    const Eigen::Vector3f hi = lo + Eigen::Vector3f(size(rng), size(rng), size(rng));
    boxes.emplace_back(lo, hi);
    m.appendSolid(boxSolid(lo, hi));
  }
  const MeshBvh bvh(m);
  int inside = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3f p(point(rng), point(rng), point(rng));
    const bool expected = std::any_of(boxes.begin(), boxes.end(),
                                      [&](const Eigen::AlignedBox3f& b) { return b.contains(p); });
    EXPECT_EQ(bvh.inside(p), expected) << p.transpose();
    inside += expected;
  }
  EXPECT_GT(inside, 100);  // the points do probe the inside
}

TEST(GeometryMeshBvh, NearestHitsMatchBruteForceOverARandomSoup) {
  const TriangleMesh soup = test::randomSoup(4000, 10.f, 0.6f, 11);
  const int hits = expectNearestHitsMatchBruteForce(soup, 15.f, 10.f, 1500, 12);
  EXPECT_GT(hits, 300);
}

TEST(GeometryMeshBvh, NearestHitsMatchBruteForceWhenEveryCentroidCoincides) {
  // Triangles (a, b, -(a + b)) with small integer coordinates: every centroid is exactly the
  // origin, so no split plane separates them and the build falls back to median splits.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> coord(-6, 6);
  TriangleMesh m;
  while (m.size() < 64) {
    const Eigen::Vector3f a(coord(rng), coord(rng), coord(rng));
    const Eigen::Vector3f b(coord(rng), coord(rng), coord(rng));
    if (a.cross(b).squaredNorm() == 0.f) continue;  // degenerate
    m.addTriangle(a, b, -(a + b), 0);
  }
  const int hits = expectNearestHitsMatchBruteForce(m, 20.f, 4.f, 1000, 4);
  EXPECT_GT(hits, 300);
}

TEST(GeometryMeshBvh, DistanceAndWithinDistanceMatchBruteForce) {
  const TriangleMesh soup = test::randomSoup(3000, 10.f, 0.6f, 21);
  const MeshBvh bvh(soup);
  const std::vector<Tri> tris = trianglesOf(soup);
  std::mt19937 rng(22);
  std::uniform_real_distribution<float> pos(-12.f, 12.f);
  int near = 0;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3f p(pos(rng), pos(rng), pos(rng));
    const float d2 = bruteDistanceSq(tris, p);
    const float max_m = 1.5f;
    EXPECT_EQ(bvh.distance(p, max_m), std::sqrt(std::min(d2, max_m * max_m))) << i;
    const float r_m = 0.8f;
    EXPECT_EQ(bvh.withinDistance(p, r_m), d2 <= r_m * r_m) << i;
    near += d2 <= r_m * r_m;
  }
  EXPECT_GT(near, 20);
  EXPECT_LT(near, 480);
}

TEST(GeometryMeshBvh, BoundsAreTheVerticesBounds) {
  TriangleMesh m;
  m.appendSolid(boxSolid({-1, 2, -3}, {0, 4, 5}));
  m.appendSolid(boxSolid({7, -8, 0}, {9, -1, 1}));
  const Eigen::AlignedBox3f b = MeshBvh(m).bounds();
  EXPECT_EQ(b.min(), Eigen::Vector3f(-1, -8, -3));
  EXPECT_EQ(b.max(), Eigen::Vector3f(9, 4, 5));
}

TEST(GeometryMeshBvh, AnEmptyMeshAnswersEveryQuery) {
  const MeshBvh bvh{TriangleMesh()};
  EXPECT_TRUE(bvh.bounds().isEmpty());
  RayHit hit;
  EXPECT_FALSE(bvh.intersect({0, 0, 0}, {1, 0, 0}, 100.f, &hit));
  EXPECT_FALSE(bvh.withinDistance({0, 0, 0}, 100.f));
  EXPECT_EQ(bvh.distance({0, 0, 0}, 7.f), 7.f);
  EXPECT_FALSE(bvh.inside({0, 0, 0}));
}

TEST(GeometryMeshBvh, MalformedMeshesAreRejected) {
  TriangleMesh missing_solid = boxSolid({0, 0, 0}, {1, 1, 1});
  missing_solid.solid_of_triangle.pop_back();
  EXPECT_THROW(MeshBvh{missing_solid}, InvalidArgument);
  TriangleMesh bad_vertex = boxSolid({0, 0, 0}, {1, 1, 1});
  bad_vertex.triangles[3][1] = 8;  // one past the last vertex
  EXPECT_THROW(MeshBvh{bad_vertex}, InvalidArgument);
  bad_vertex.triangles[3][1] = -1;
  EXPECT_THROW(MeshBvh{bad_vertex}, InvalidArgument);
}

TEST(GeometryMeshBvh, InsideCountsAtMost32SolidsAboveAPoint) {
  // Thin wide slabs stacked above the origin: the inside ray (steep upwards) crosses each.
  auto stack = [](int slabs) {
    TriangleMesh m;
    for (int i = 0; i < slabs; ++i)
      m.appendSolid(boxSolid({-20, -20, 1.f + i}, {20, 20, 1.5f + i}));
    return MeshBvh(m);
  };
  EXPECT_FALSE(stack(32).inside({0, 0, 0}));
  EXPECT_TRUE(stack(32).inside({0, 0, 1.25f}));
  EXPECT_THROW(stack(33).inside({0, 0, 0}), InvalidArgument);
}

}  // namespace
}  // namespace fragg::geometry
