#include "geometry/closed_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <tuple>

#include "core/errors.hpp"
#include "geometry/wall_distance.hpp"

namespace grainscale {

namespace {

// 2-D orientation in the (y, z) plane: > 0 when p lies left of a -> b.
Real orient_yz(const Vec3& a, const Vec3& b, const Vec3& p) {
  return (b[1] - a[1]) * (p[2] - a[2]) - (b[2] - a[2]) * (p[1] - a[1]);
}

// Vertex ids after merging vertices with identical coordinates (the lowest id of each group).
std::vector<int> merged_ids(const std::vector<Vec3>& v) {
  std::vector<int> order(v.size());
  std::iota(order.begin(), order.end(), 0);
  auto less = [&](int a, int b) {
    return std::lexicographical_compare(v[a].data(), v[a].data() + 3, v[b].data(),
                                        v[b].data() + 3) ||
           (v[a] == v[b] && a < b);
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<int> id(v.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    id[order[k]] = (k > 0 && v[order[k]] == v[order[k - 1]]) ? id[order[k - 1]] : order[k];
  return id;
}

}  // namespace

ClosedMesh::ClosedMesh(const std::vector<Vec3>& vertices,
                       const std::vector<std::array<int, 3>>& triangles, const std::string& what) {
  if (triangles.size() < 4)
    throw_invalid(what, "a closed surface of at least 4 triangles",
                  std::to_string(triangles.size()) + " triangles");
  const int nv = static_cast<int>(vertices.size());
  for (const Vec3& v : vertices)
    if (!v.allFinite()) throw_invalid(what + " vertices", "finite (m)", v.transpose());
  for (const auto& t : triangles)
    for (int k : t)
      if (k < 0 || k >= nv)
        throw_invalid(what + " triangles", "vertex indices in [0, " + std::to_string(nv) + ")", k);
  const std::vector<int> id = merged_ids(vertices);
  mesh_.vertices = vertices;
  mesh_.triangles.reserve(triangles.size());
  for (const auto& t : triangles) {
    const std::array<int, 3> m{id[t[0]], id[t[1]], id[t[2]]};
    if (m[0] == m[1] || m[1] == m[2] || m[0] == m[2])
      throw_invalid(what + " triangles", "non-degenerate (three distinct vertices)",
                    std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]));
    mesh_.triangles.push_back(m);
  }

  // Each directed edge (a, b) of each triangle; a closed, consistently oriented surface holds
  // every undirected edge exactly twice, once in each direction.
  struct Edge {
    int lo, hi, forward, triangle;
  };
  std::vector<Edge> edges;
  edges.reserve(3 * mesh_.triangles.size());
  for (int t = 0; t < static_cast<int>(mesh_.triangles.size()); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh_.triangles[t][k], b = mesh_.triangles[t][(k + 1) % 3];
      edges.push_back({std::min(a, b), std::max(a, b), a < b ? 1 : 0, t});
    }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    return std::tie(x.lo, x.hi, x.forward, x.triangle) <
           std::tie(y.lo, y.hi, y.forward, y.triangle);
  });
  std::size_t open = 0, crowded = 0, flipped = 0;
  std::string example_open, example_crowded, example_flipped;
  auto pair_text = [](int a, int b) {
    return "vertices " + std::to_string(a) + " and " + std::to_string(b);
  };
  for (std::size_t k = 0; k < edges.size();) {
    std::size_t end = k;
    while (end < edges.size() && edges[end].lo == edges[k].lo && edges[end].hi == edges[k].hi)
      ++end;
    const std::size_t n = end - k;
    if (n == 1 && open++ == 0) example_open = pair_text(edges[k].lo, edges[k].hi);
    if (n > 2 && crowded++ == 0) example_crowded = pair_text(edges[k].lo, edges[k].hi);
    if (n == 2 && edges[k].forward == edges[k + 1].forward && flipped++ == 0)
      example_flipped = "triangles " + std::to_string(edges[k].triangle) + " and " +
                        std::to_string(edges[k + 1].triangle);
    k = end;
  }
  if (open > 0)
    throw_invalid(what, "a closed surface (every edge shared by exactly two triangles)",
                  std::to_string(open) + " open edges (e.g. between " + example_open + ")");
  if (crowded > 0)
    throw_invalid(what, "a closed surface (every edge shared by exactly two triangles)",
                  std::to_string(crowded) + " edges shared by more than two triangles (e.g. " +
                      example_crowded + ")");
  if (flipped > 0)
    throw_invalid(what,
                  "consistently oriented (two triangles sharing an edge traverse it in opposite "
                  "directions)",
                  std::to_string(flipped) +
                      " edges traversed twice in the same direction (e.g. by " + example_flipped +
                      ")");

  Real six_v = 0;
  lo_ = hi_ = vertices[mesh_.triangles[0][0]];
  for (const auto& t : mesh_.triangles) {
    const Vec3 &a = mesh_.vertices[t[0]], &b = mesh_.vertices[t[1]], &c = mesh_.vertices[t[2]];
    six_v += a.dot(b.cross(c));
    for (int k = 0; k < 3; ++k) {
      lo_ = lo_.cwiseMin(mesh_.vertices[t[k]]);
      hi_ = hi_.cwiseMax(mesh_.vertices[t[k]]);
    }
  }
  volume_ = std::abs(six_v) / 6;
  if (!(volume_ > 0)) throw_invalid(what, "enclosing a positive volume (m^3)", volume_);

  bins_.build(mesh_.vertices, mesh_.triangles, {}, 0, 0);
  std::vector<Vec3> flat(mesh_.vertices);
  for (Vec3& v : flat) v[0] = 0;
  ray_bins_.build(flat, mesh_.triangles, {}, 0, 0);
}

bool ClosedMesh::ray_crosses(int t, const Vec3& x) const {
  const auto& V = mesh_.vertices;
  std::array<int, 3> v = mesh_.triangles[t];
  const Real area = orient_yz(V[v[0]], V[v[1]], V[v[2]]);
  if (area == 0) return false;          // parallel to the ray: its neighbours decide
  if (area < 0) std::swap(v[1], v[2]);  // counter-clockwise in (y, z): inside is left of edges
  Real weight[3];
  for (int e = 0; e < 3; ++e) {
    const int a = v[e], b = v[(e + 1) % 3];
    // Computed in canonical order so both triangles of an edge see the same number.
    const int i = std::min(a, b), j = std::max(a, b);
    Real side = orient_yz(V[i], V[j], x);
    Real dy = V[j][1] - V[i][1], dz = V[j][2] - V[i][2];
    if (a != i) {
      side = -side;
      dy = -dy;
      dz = -dz;
    }
    // On the edge line: the shifted ray x + (0, e, e^2) is left of a -> b iff
    // dy e^2 - dz e > 0 for small e.
    if (side < 0 || (side == 0 && !(dz < 0 || (dz == 0 && dy > 0)))) return false;
    weight[(e + 2) % 3] = side;  // barycentric weight of the vertex opposite the edge
  }
  const Real sum = weight[0] + weight[1] + weight[2];
  if (!(sum > 0)) return false;
  const Real hit = (weight[0] * V[v[0]][0] + weight[1] * V[v[1]][0] + weight[2] * V[v[2]][0]) / sum;
  return hit > x[0];
}

bool ClosedMesh::inside(const Vec3& x) const {
  ray_bins_.candidates(Vec3(0, x[1], x[2]), scratch_);
  bool in = false;
  for (int t : scratch_)
    if (ray_crosses(t, x)) in = !in;
  return in;
}

bool ClosedMesh::near_surface(const Vec3& x, Real r) const {
  if (!(r > 0)) return false;
  bins_.candidates(x - Vec3::Constant(r), x + Vec3::Constant(r), scratch_);
  return mesh_distance(mesh_, scratch_, x, r) < r;
}

}  // namespace grainscale
