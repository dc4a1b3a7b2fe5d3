#include "fragg_map/sim/primitives.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "fragg_map/errors.h"

namespace fragg::sim {

using geometry::TriangleMesh;

namespace {

int32_t addVertex(TriangleMesh& m, const Eigen::Vector3d& p) {
  m.vertices_m.push_back(p.cast<float>());
  return static_cast<int32_t>(m.vertices_m.size()) - 1;
}

void addTri(TriangleMesh& m, int32_t a, int32_t b, int32_t c) {
  m.triangles.emplace_back(a, b, c);
  m.solid_of_triangle.push_back(0);
}

// Two triangles for the quad a b c d (counter-clockwise seen from outside).
void addQuad(TriangleMesh& m, int32_t a, int32_t b, int32_t c, int32_t d) {
  addTri(m, a, b, c);
  addTri(m, a, c, d);
}

TriangleMesh solid() {
  TriangleMesh m;
  m.solid_count = 1;
  return m;
}

}  // namespace

TriangleMesh makeOrientedBox(const Eigen::Vector3d& centre_m, const Eigen::Vector3d& half_m,
                             double yaw_rad) {
  if (!(half_m.array() > 0).all()) throw InvalidArgument("box: every half extent must be > 0");
  TriangleMesh m = solid();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).matrix();
  int32_t v[8];
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d s((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
    v[i] = addVertex(m, centre_m + R * s.cwiseProduct(half_m));
  }
  addQuad(m, v[0], v[2], v[3], v[1]);  // z-
  addQuad(m, v[4], v[5], v[7], v[6]);  // z+
  addQuad(m, v[0], v[1], v[5], v[4]);  // y-
  addQuad(m, v[2], v[6], v[7], v[3]);  // y+
  addQuad(m, v[0], v[4], v[6], v[2]);  // x-
  addQuad(m, v[1], v[3], v[7], v[5]);  // x+
  return m;
}

TriangleMesh makeBox(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m) {
  return makeOrientedBox(0.5 * (min_m + max_m), 0.5 * (max_m - min_m), 0.0);
}

TriangleMesh makeCylinder(const Eigen::Vector3d& a_m, const Eigen::Vector3d& b_m, double radius_m,
                          int segments) {
  const Eigen::Vector3d axis = b_m - a_m;
  if (!(radius_m > 0) || axis.norm() <= 0 || segments < 3)
    throw InvalidArgument("cylinder: needs radius > 0, two distinct ends and >= 3 segments");
  const Eigen::Vector3d w = axis.normalized();
  const Eigen::Vector3d u = w.unitOrthogonal();
  const Eigen::Vector3d v = w.cross(u);
  TriangleMesh m = solid();
  const int32_t ca = addVertex(m, a_m), cb = addVertex(m, b_m);
  std::vector<int32_t> ring_a(segments), ring_b(segments);
  for (int i = 0; i < segments; ++i) {
    const double phi = 2.0 * M_PI * i / segments;
    const Eigen::Vector3d r = radius_m * (std::cos(phi) * u + std::sin(phi) * v);
    ring_a[i] = addVertex(m, a_m + r);
    ring_b[i] = addVertex(m, b_m + r);
  }
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    addQuad(m, ring_a[i], ring_a[j], ring_b[j], ring_b[i]);
    addTri(m, ca, ring_a[j], ring_a[i]);
    addTri(m, cb, ring_b[i], ring_b[j]);
  }
  return m;
}

TriangleMesh makeSphere(const Eigen::Vector3d& centre_m, double radius_m, int rings, int segments) {
  if (!(radius_m > 0) || rings < 2 || segments < 3)
    throw InvalidArgument("sphere: needs radius > 0, >= 2 rings and >= 3 segments");
  TriangleMesh m = solid();
  const int32_t south = addVertex(m, centre_m - Eigen::Vector3d(0, 0, radius_m));
  const int32_t north = addVertex(m, centre_m + Eigen::Vector3d(0, 0, radius_m));
  std::vector<std::vector<int32_t>> ring(rings - 1, std::vector<int32_t>(segments));
  for (int r = 1; r < rings; ++r) {
    const double theta = -M_PI / 2 + M_PI * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2.0 * M_PI * s / segments;
      ring[r - 1][s] =
          addVertex(m, centre_m + radius_m * Eigen::Vector3d(std::cos(theta) * std::cos(phi),
                                                             std::cos(theta) * std::sin(phi),
                                                             std::sin(theta)));
    }
  }
  for (int s = 0; s < segments; ++s) {
    const int t = (s + 1) % segments;
    addTri(m, south, ring[0][t], ring[0][s]);
    addTri(m, north, ring[rings - 2][s], ring[rings - 2][t]);
    for (int r = 0; r + 1 < rings - 1; ++r)
      addQuad(m, ring[r][s], ring[r][t], ring[r + 1][t], ring[r + 1][s]);
  }
  return m;
}

TriangleMesh makeTerrainSlab(double x0, double y0, double x1, double y1, double cell_m,
                             double thickness_m,
                             const std::function<double(double, double)>& height_m) {
  if (!(x1 > x0) || !(y1 > y0) || !(cell_m > 0) || !(thickness_m > 0))
    throw InvalidArgument("ground: needs a non-empty extent, cell > 0 and thickness > 0");
  const int nx = std::max(1, static_cast<int>(std::ceil((x1 - x0) / cell_m)));
  const int ny = std::max(1, static_cast<int>(std::ceil((y1 - y0) / cell_m)));
  TriangleMesh m = solid();
  std::vector<int32_t> top((nx + 1) * (ny + 1)), bottom((nx + 1) * (ny + 1));
  double z_low = INFINITY;
  std::vector<Eigen::Vector3d> samples;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = x0 + (x1 - x0) * i / nx, y = y0 + (y1 - y0) * j / ny;
      samples.emplace_back(x, y, height_m(x, y));
      z_low = std::min(z_low, samples.back().z());
    }
  const double z_bottom = z_low - thickness_m;
  for (size_t k = 0; k < samples.size(); ++k) {
    top[k] = addVertex(m, samples[k]);
    bottom[k] = addVertex(m, {samples[k].x(), samples[k].y(), z_bottom});
  }
  auto at = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      addQuad(m, top[at(i, j)], top[at(i + 1, j)], top[at(i + 1, j + 1)], top[at(i, j + 1)]);
      addQuad(m, bottom[at(i, j)], bottom[at(i, j + 1)], bottom[at(i + 1, j + 1)],
              bottom[at(i + 1, j)]);
    }
  for (int i = 0; i < nx; ++i) {  // sides y0 and y1
    addQuad(m, bottom[at(i, 0)], bottom[at(i + 1, 0)], top[at(i + 1, 0)], top[at(i, 0)]);
    addQuad(m, bottom[at(i + 1, ny)], bottom[at(i, ny)], top[at(i, ny)], top[at(i + 1, ny)]);
  }
  for (int j = 0; j < ny; ++j) {  // sides x0 and x1
    addQuad(m, bottom[at(0, j + 1)], bottom[at(0, j)], top[at(0, j)], top[at(0, j + 1)]);
    addQuad(m, bottom[at(nx, j)], bottom[at(nx, j + 1)], top[at(nx, j + 1)], top[at(nx, j)]);
  }
  return m;
}

}  // namespace fragg::sim
