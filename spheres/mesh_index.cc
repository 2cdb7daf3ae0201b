#include "spheres/mesh_index.h"

#include <algorithm>
#include <cstring>
#include <numeric>
#include <unordered_map>

namespace flowplan::spheres {
namespace {

using internal::Vec3;

constexpr int kLeafSize = 8;

uint64_t Bits(double x) {
  x += 0.0;  // -0.0 and 0.0 are one position
  uint64_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  return bits;
}

struct PositionKey {
  uint64_t bits[3];
  bool operator==(const PositionKey& o) const {
    return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
  }
};

struct PositionHash {
  size_t operator()(const PositionKey& key) const {
    uint64_t h = 0x9E3779B97F4A7C15ULL;
    for (uint64_t b : key.bits) h = (h ^ b) * 0x100000001B3ULL + (h >> 29);
    return static_cast<size_t>(h);
  }
};

bool OutsideBox(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return p.x < lo.x || p.y < lo.y || p.z < lo.z || p.x > hi.x || p.y > hi.y || p.z > hi.z;
}

}  // namespace

MeshIndex::MeshIndex(const Mesh& mesh) {
  ValidateMesh(mesh);
  // Weld corners at the same position, so that patches have short boundaries.
  std::unordered_map<PositionKey, int, PositionHash> welded;
  std::vector<int> remap(mesh.vertices.size());
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const auto& p = mesh.vertices[v];
    const PositionKey key{{Bits(p[0]), Bits(p[1]), Bits(p[2])}};
    const auto [it, inserted] = welded.emplace(key, static_cast<int>(points_.size()));
    if (inserted) points_.emplace_back(p);
    remap[v] = it->second;
  }
  std::vector<std::array<int, 3>> triangles;
  triangles.reserve(mesh.triangles.size());
  std::vector<Vec3> centroids;
  centroids.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    const std::array<int, 3> w = {remap[t[0]], remap[t[1]], remap[t[2]]};
    triangles.push_back(w);
    centroids.push_back((points_[w[0]] + points_[w[1]] + points_[w[2]]) * (1.0 / 3.0));
  }
  triangles_ = triangles;
  std::vector<int> order(triangles.size());
  std::iota(order.begin(), order.end(), 0);
  nodes_.reserve(2 * triangles.size() / kLeafSize + 2);
  Build(order, centroids, 0, static_cast<int>(order.size()));
  for (size_t i = 0; i < order.size(); ++i) triangles_[i] = triangles[order[i]];
  for (Node& node : nodes_) {
    if (node.left >= 0) BuildCap(node);
  }
}

int MeshIndex::Build(std::vector<int>& order, const std::vector<Vec3>& centroids, int first, int count) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Vec3 lo(INFINITY, INFINITY, INFINITY), hi(-INFINITY, -INFINITY, -INFINITY);
  Vec3 clo = lo, chi = hi;
  for (int i = first; i < first + count; ++i) {
    for (int k : triangles_[order[i]]) {
      lo = Min(lo, points_[k]);
      hi = Max(hi, points_[k]);
    }
    clo = Min(clo, centroids[order[i]]);
    chi = Max(chi, centroids[order[i]]);
  }
  nodes_[index].lo = lo;
  nodes_[index].hi = hi;
  nodes_[index].first = first;
  nodes_[index].count = count;
  if (count <= kLeafSize) return index;
  const Vec3 extent = chi - clo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const int half = count / 2;
  // Ties broken by triangle index so that the hierarchy does not depend on the library's nth_element.
  std::nth_element(order.begin() + first, order.begin() + first + half, order.begin() + first + count,
                   [&](int a, int b) {
                     const double ca = centroids[a][axis], cb = centroids[b][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  const int left = Build(order, centroids, first, half);
  const int right = Build(order, centroids, first + half, count - half);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

void MeshIndex::BuildCap(Node& node) {
  // Directed edges keyed by their unordered pair; +1 for a -> b with a < b, -1 otherwise.
  std::vector<std::pair<uint64_t, int>> edges;
  edges.reserve(3 * static_cast<size_t>(node.count));
  for (int t = node.first; t < node.first + node.count; ++t) {
    const auto& tri = triangles_[t];
    for (int k = 0; k < 3; ++k) {
      const auto a = static_cast<uint64_t>(tri[k]), b = static_cast<uint64_t>(tri[(k + 1) % 3]);
      if (a == b) continue;
      if (a < b) {
        edges.emplace_back((a << 32) | b, 1);
      } else {
        edges.emplace_back((b << 32) | a, -1);
      }
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<CapEdge> boundary;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    int net = 0;
    while (j < edges.size() && edges[j].first == edges[i].first) net += edges[j++].second;
    if (net != 0) {
      const int lo = static_cast<int>(edges[i].first >> 32), hi = static_cast<int>(edges[i].first & 0xffffffffULL);
      boundary.push_back(net > 0 ? CapEdge{lo, hi, net} : CapEdge{hi, lo, -net});
    }
    i = j;
  }
  if (static_cast<int>(boundary.size()) >= node.count) return;  // summing the triangles is cheaper
  node.cap_first = static_cast<int>(cap_edges_.size());
  node.cap_count = static_cast<int>(boundary.size());
  node.cap_apex = boundary.empty() ? 0 : boundary[0].a;
  cap_edges_.insert(cap_edges_.end(), boundary.begin(), boundary.end());
}

double MeshIndex::DistanceTo(const Vec3& p, Vec3* closest) const {
  double best2 = INFINITY;
  Vec3 best_point;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (SquaredDistanceToBox(p, node.lo, node.hi) >= best2) continue;
    if (node.left < 0) {
      for (int t = node.first; t < node.first + node.count; ++t) {
        const auto& tri = triangles_[t];
        const Vec3 q = internal::ClosestPointOnTriangle(p, points_[tri[0]], points_[tri[1]], points_[tri[2]]);
        const double d2 = SquaredDistance(p, q);
        if (d2 < best2) {
          best2 = d2;
          best_point = q;
        }
      }
      continue;
    }
    const Node& left = nodes_[node.left];
    const Node& right = nodes_[node.right];
    const double dl = SquaredDistanceToBox(p, left.lo, left.hi), dr = SquaredDistanceToBox(p, right.lo, right.hi);
    // The nearer child is visited first (pushed last).
    if (dl <= dr) {
      stack[top++] = node.right;
      stack[top++] = node.left;
    } else {
      stack[top++] = node.left;
      stack[top++] = node.right;
    }
  }
  if (closest != nullptr) *closest = best_point;
  return std::sqrt(best2);
}

double MeshIndex::WindingNumberAt(const Vec3& p) const {
  double total = 0.0;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (node.cap_count >= 0 && OutsideBox(p, node.lo, node.hi)) {
      const Vec3& apex = points_[node.cap_apex];
      for (int e = node.cap_first; e < node.cap_first + node.cap_count; ++e) {
        const CapEdge& edge = cap_edges_[e];
        total += edge.weight * internal::SolidAngle(p, apex, points_[edge.a], points_[edge.b]);
      }
      continue;
    }
    if (node.left < 0) {
      for (int t = node.first; t < node.first + node.count; ++t) {
        const auto& tri = triangles_[t];
        total += internal::SolidAngle(p, points_[tri[0]], points_[tri[1]], points_[tri[2]]);
      }
      continue;
    }
    stack[top++] = node.right;
    stack[top++] = node.left;
  }
  return total / (4.0 * M_PI);
}

double MeshIndex::Distance(const std::array<double, 3>& p) const { return DistanceTo(Vec3(p)); }

std::array<double, 3> MeshIndex::ClosestPoint(const std::array<double, 3>& p) const {
  Vec3 closest;
  DistanceTo(Vec3(p), &closest);
  return closest.array();
}

double MeshIndex::WindingNumber(const std::array<double, 3>& p) const { return WindingNumberAt(Vec3(p)); }

}  // namespace flowplan::spheres
