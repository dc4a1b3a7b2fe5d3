#include "fragg_map/geometry/mesh_bvh.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/bvh_traversal.h"

namespace fragg::geometry {
namespace {

constexpr uint32_t kLeafSize = 4;
constexpr int kBins = 16;
// SAH splits down to kMaxSahDepth, median splits below (depth <= 48 + log2(n) < kStackSize).
constexpr int kMaxSahDepth = 48;
constexpr int kStackSize = 96;
constexpr float kEdgeEps = 1e-5f;

// Slab test; returns the entry distance or INFINITY when the box is missed within [0, t_max].
inline float boxEntry(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                      const Eigen::Vector3f& origin, const Eigen::Vector3f& inv_dir, float t_max) {
  float t0 = 0.f, t1 = t_max;
  for (int a = 0; a < 3; ++a) {
    float near = (lo[a] - origin[a]) * inv_dir[a];
    float far = (hi[a] - origin[a]) * inv_dir[a];
    if (near > far) std::swap(near, far);
    if (std::isnan(near)) near = -INFINITY;  // 0 * inf: origin on the slab plane
    if (std::isnan(far)) far = INFINITY;
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
    if (t0 > t1) return INFINITY;
  }
  return t0;
}

inline float boxDistanceSq(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                           const Eigen::Vector3f& p) {
  const Eigen::Vector3f d = (lo - p).cwiseMax(p - hi).cwiseMax(0.f);
  return d.squaredNorm();
}

}  // namespace

MeshBvh::MeshBvh(TriangleMesh mesh) : mesh_(std::move(mesh)) {
  if (mesh_.solid_of_triangle.size() != mesh_.triangles.size())
    throw InvalidArgument("mesh: one solid id per triangle is required");
  const size_t n = mesh_.triangles.size();
  for (const Eigen::Vector3i& t : mesh_.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || static_cast<size_t>(t[k]) >= mesh_.vertices_m.size())
        throw InvalidArgument("mesh: a triangle refers to a vertex that does not exist");
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0u);
  std::vector<Eigen::Vector3f> centroids(n);
  std::vector<Eigen::AlignedBox3f> boxes(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3i& t = mesh_.triangles[i];
    centroids[i] = (mesh_.vertices_m[t[0]] + mesh_.vertices_m[t[1]] + mesh_.vertices_m[t[2]]) / 3.f;
    for (int k = 0; k < 3; ++k) boxes[i].extend(mesh_.vertices_m[t[k]]);
  }
  nodes_.reserve(2 * n / kLeafSize + 2);
  if (n > 0) build(0, static_cast<uint32_t>(n), centroids, boxes, 0);
  tris_.resize(n);
  solid_of_slot_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    solid_of_slot_[i] = mesh_.solid_of_triangle[order_[i]];
    const Eigen::Vector3i& t = mesh_.triangles[order_[i]];
    const Eigen::Vector3f& a = mesh_.vertices_m[t[0]];
    tris_[i] = {a, mesh_.vertices_m[t[1]] - a, mesh_.vertices_m[t[2]] - a};
  }
}

uint32_t MeshBvh::build(uint32_t begin, uint32_t end, const std::vector<Eigen::Vector3f>& centroids,
                        const std::vector<Eigen::AlignedBox3f>& boxes, int depth) {
  const uint32_t index = static_cast<uint32_t>(nodes_.size());
  nodes_.emplace_back();
  Eigen::AlignedBox3f box, cbox;
  for (uint32_t i = begin; i < end; ++i) {
    box.extend(boxes[order_[i]]);
    cbox.extend(centroids[order_[i]]);
  }
  nodes_[index].lo = box.min();
  nodes_[index].hi = box.max();
  const uint32_t n = end - begin;
  auto makeLeaf = [&] {
    nodes_[index].first = begin;
    nodes_[index].count = n;
    return index;
  };
  if (n <= kLeafSize) return makeLeaf();

  // Binned surface area heuristic: the split plane (kBins per axis) that minimises
  // area(left) * n_left + area(right) * n_right.
  auto area = [](const Eigen::AlignedBox3f& b) {
    if (b.isEmpty()) return 0.f;
    const Eigen::Vector3f d = b.sizes();
    return d.x() * d.y() + d.y() * d.z() + d.z() * d.x();
  };
  float best_cost = INFINITY;
  int best_axis = -1, best_split = 0;
  const Eigen::Vector3f extent = cbox.sizes();
  for (int axis = 0; axis < 3; ++axis) {
    if (!(extent[axis] > 0)) continue;
    Eigen::AlignedBox3f bin_box[kBins];
    uint32_t bin_count[kBins] = {};
    const float scale = kBins / extent[axis];
    for (uint32_t i = begin; i < end; ++i) {
      const int bin =
          std::min(kBins - 1, int((centroids[order_[i]][axis] - cbox.min()[axis]) * scale));
      bin_box[bin].extend(boxes[order_[i]]);
      ++bin_count[bin];
    }
    float right_area[kBins];
    uint32_t right_count[kBins];
    Eigen::AlignedBox3f acc;
    uint32_t count = 0;
    for (int b = kBins - 1; b > 0; --b) {
      acc.extend(bin_box[b]);
      count += bin_count[b];
      right_area[b] = area(acc);
      right_count[b] = count;
    }
    acc.setEmpty();
    count = 0;
    for (int b = 0; b < kBins - 1; ++b) {
      acc.extend(bin_box[b]);
      count += bin_count[b];
      if (count == 0 || right_count[b + 1] == 0) continue;
      const float cost = area(acc) * count + right_area[b + 1] * right_count[b + 1];
      if (cost < best_cost) {
        best_cost = cost;
        best_axis = axis;
        best_split = b;
      }
    }
  }
  uint32_t mid = begin + n / 2;
  if (depth >= kMaxSahDepth || best_axis < 0) {
    // Deep (or all centroids in one point): a median split bounds the depth by log2(n).
    int axis = 0;
    extent.maxCoeff(&axis);
    std::nth_element(
        order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
        [&](uint32_t a, uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
  } else {
    const float lo = cbox.min()[best_axis], scale = kBins / extent[best_axis];
    mid = static_cast<uint32_t>(
        std::partition(order_.begin() + begin, order_.begin() + end,
                       [&](uint32_t t) {
                         return std::min(kBins - 1, int((centroids[t][best_axis] - lo) * scale)) <=
                                best_split;
                       }) -
        order_.begin());
    if (mid == begin || mid == end) mid = begin + n / 2;
  }
  build(begin, mid, centroids, boxes, depth + 1);
  const uint32_t right = build(mid, end, centroids, boxes, depth + 1);
  nodes_[index].first = right;
  nodes_[index].count = 0;
  return index;
}

Eigen::AlignedBox3f MeshBvh::bounds() const {
  if (nodes_.empty()) return Eigen::AlignedBox3f();
  return Eigen::AlignedBox3f(nodes_[0].lo, nodes_[0].hi);
}

template <typename Visit>
void MeshBvh::traverseRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t_max,
                          float edge_eps, Visit&& visit) const {
  // visit(leaf slot, t) may lower t_max (nearest hit) through its return value.
  if (nodes_.empty()) return;
  const Eigen::Vector3f inv_dir = dir.cwiseInverse();
  uint32_t stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (boxEntry(node.lo, node.hi, origin, inv_dir, t_max) == INFINITY) continue;
    if (node.count > 0) {
      for (uint32_t i = node.first; i < node.first + node.count; ++i) {
        const float t = rayTriangle(origin, dir, tris_[i].v0, tris_[i].e1, tris_[i].e2, edge_eps);
        if (t > 0.f && t < t_max) t_max = visit(i, t, t_max);
      }
      continue;
    }
    const uint32_t left = static_cast<uint32_t>(&node - nodes_.data()) + 1, right = node.first;
    const float tl = boxEntry(nodes_[left].lo, nodes_[left].hi, origin, inv_dir, t_max);
    const float tr = boxEntry(nodes_[right].lo, nodes_[right].hi, origin, inv_dir, t_max);
    // Push the farther child first so that the nearer one is visited first.
    if (tl <= tr) {
      if (tr != INFINITY) stack[top++] = right;
      if (tl != INFINITY) stack[top++] = left;
    } else {
      if (tl != INFINITY) stack[top++] = left;
      if (tr != INFINITY) stack[top++] = right;
    }
  }
}

bool MeshBvh::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir_unit,
                        float t_max_m, RayHit* hit) const {
  int32_t best = -1;
  float best_t = t_max_m;
  // A ray through the edge shared by two triangles must hit one of them: a small tolerance
  // on the barycentric limits closes the cracks float rounding opens there.
  traverseRay(origin, dir_unit, t_max_m, kEdgeEps, [&](uint32_t slot, float t, float) {
    best = static_cast<int32_t>(slot);
    best_t = t;
    return t;
  });
  if (best < 0) return false;
  if (hit) *hit = {best_t, static_cast<int32_t>(order_[best])};
  return true;
}

bool MeshBvh::inside(const Eigen::Vector3f& p) const {
  if (nodes_.empty()) return false;
  bool overflow = false;
  const bool in = bvhInside(nodes_.data(), tris_.data(), solid_of_slot_.data(), p,
                            insideRayDirection(), &overflow);
  if (overflow) throw InvalidArgument("inside test: more than 32 solids above one point");
  return in;
}

bool MeshBvh::withinDistance(const Eigen::Vector3f& p, float r_m) const {
  if (nodes_.empty()) return false;
  const float r2 = r_m * r_m;
  uint32_t stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (boxDistanceSq(node.lo, node.hi, p) > r2) continue;
    if (node.count > 0) {
      for (uint32_t i = node.first; i < node.first + node.count; ++i) {
        const Tri& t = tris_[i];
        if (pointTriangleDistanceSq(p, t.v0, t.v0 + t.e1, t.v0 + t.e2) <= r2) return true;
      }
      continue;
    }
    stack[top++] = node.first;
    stack[top++] = static_cast<uint32_t>(&node - nodes_.data()) + 1;
  }
  return false;
}

float MeshBvh::distance(const Eigen::Vector3f& p, float max_m) const {
  float best2 = max_m * max_m;
  if (nodes_.empty()) return max_m;
  uint32_t stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (boxDistanceSq(node.lo, node.hi, p) >= best2) continue;
    if (node.count > 0) {
      for (uint32_t i = node.first; i < node.first + node.count; ++i) {
        const Tri& t = tris_[i];
        best2 = std::min(best2, pointTriangleDistanceSq(p, t.v0, t.v0 + t.e1, t.v0 + t.e2));
      }
      continue;
    }
    const uint32_t left = static_cast<uint32_t>(&node - nodes_.data()) + 1, right = node.first;
    const float dl = boxDistanceSq(nodes_[left].lo, nodes_[left].hi, p);
    const float dr = boxDistanceSq(nodes_[right].lo, nodes_[right].hi, p);
    if (dl <= dr) {
      stack[top++] = right;
      stack[top++] = left;
    } else {
      stack[top++] = left;
      stack[top++] = right;
    }
  }
  return std::sqrt(best2);
}

}  // namespace fragg::geometry
