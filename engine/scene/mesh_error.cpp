#include "visbuf/scene/mesh_error.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace visbuf {

double pointTriangleDistance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return glm::length(p - a);
  const glm::dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return glm::length(p - b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return glm::length(p - (a + ab * (d1 / (d1 - d3))));
  const glm::dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return glm::length(p - c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return glm::length(p - (a + ac * (d2 / (d2 - d6))));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  const double denom = 1.0 / (va + vb + vc);
  if (!std::isfinite(denom)) {  // degenerate triangle: nearest of its edges' endpoints is a fine bound
    return std::min({glm::length(p - a), glm::length(p - b), glm::length(p - c)});
  }
  return glm::length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

TriangleBvh::TriangleBvh(std::span<const glm::vec3> positions, std::span<const uint32_t> indices)
    : positions_(positions), indices_(indices) {
  // Lod::indexCount is 32-bit, so a mesh's triangle numbers fit 32 bits (buildMesh refuses more).
  const uint32_t tris = uint32_t(indices.size() / 3);
  if (tris == 0) return;
  std::vector<glm::vec3> centroid(tris);
  order_.resize(tris);
  for (uint32_t t = 0; t < tris; ++t) {
    order_[t] = t;
    centroid[t] = (positions[indices[3 * t]] + positions[indices[3 * t + 1]] + positions[indices[3 * t + 2]]) / 3.0f;
  }
  nodes_.reserve(size_t(tris) / 2 + 2);
  build(0, tris, centroid);
}

uint32_t TriangleBvh::build(uint32_t first, uint32_t count, std::vector<glm::vec3>& centroid) {
  constexpr uint32_t kLeafTriangles = 4;
  const uint32_t self = uint32_t(nodes_.size());
  nodes_.push_back({});
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  glm::vec3 clo = lo, chi = hi;
  for (uint32_t k = first; k < first + count; ++k) {
    const uint32_t t = order_[k];
    for (int c = 0; c < 3; ++c) {
      lo = glm::min(lo, positions_[indices_[3 * t + c]]);
      hi = glm::max(hi, positions_[indices_[3 * t + c]]);
    }
    clo = glm::min(clo, centroid[t]);
    chi = glm::max(chi, centroid[t]);
  }
  nodes_[self].lo = lo;
  nodes_[self].hi = hi;
  if (count <= kLeafTriangles) {
    nodes_[self].first = first;
    nodes_[self].count = count;
    return self;
  }
  // Median split by count along the centroids' longest axis: both halves are non-empty and at most half (rounded
  // up), whatever the geometry (coincident triangles included), so the depth is logarithmic.
  const glm::vec3 ext = chi - clo;
  const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
  const uint32_t half = count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                   [&](uint32_t a, uint32_t b) { return centroid[a][axis] < centroid[b][axis]; });
  build(first, half, centroid);
  const uint32_t second = build(first + half, count - half, centroid);
  nodes_[self].first = second;
  nodes_[self].count = 0;
  return self;
}

namespace {

// Distance from p to the box [lo, hi] (0 inside).
double boxDistance(const glm::dvec3& p, const glm::vec3& lo, const glm::vec3& hi) {
  const glm::dvec3 d = glm::max(glm::max(glm::dvec3(lo) - p, p - glm::dvec3(hi)), glm::dvec3(0.0));
  return glm::length(d);
}

}  // namespace

double TriangleBvh::distance(const glm::dvec3& p, double enough) const { return search(p, enough, nullptr); }

double TriangleBvh::distance(const glm::dvec3& p, double enough, uint64_t& budget) const {
  return search(p, enough, &budget);
}

double TriangleBvh::search(const glm::dvec3& p, double enough, uint64_t* budget) const {
  double best = std::numeric_limits<double>::max();
  if (nodes_.empty()) return best;
  // Depth-first, nearer child first; a subtree whose box is no nearer than the best triangle so far is skipped.
  // The depth is at most log2(2^32) + 1, so each pending level holds one deferred sibling: 64 slots suffice.
  struct Pending {
    uint32_t node;
    double boxDist;
  };
  Pending stack[64];
  int top = 0;
  stack[top++] = {0, boxDistance(p, nodes_[0].lo, nodes_[0].hi)};
  while (top > 0) {
    const Pending cur = stack[--top];
    if (cur.boxDist >= best) continue;
    if (budget) {
      if (*budget == 0 && best < std::numeric_limits<double>::max()) return best;  // an upper bound
      if (*budget > 0) --*budget;
    }
    const Node& n = nodes_[cur.node];
    if (n.count > 0) {
      for (uint32_t k = n.first; k < n.first + n.count; ++k) {
        const uint32_t t = order_[k];
        best = std::min(best, pointTriangleDistance(p, glm::dvec3(positions_[indices_[3 * t]]),
                                                    glm::dvec3(positions_[indices_[3 * t + 1]]),
                                                    glm::dvec3(positions_[indices_[3 * t + 2]])));
        if (best <= enough) return best;
      }
      if (budget && *budget > 0) *budget -= std::min<uint64_t>(*budget, n.count);
      continue;
    }
    const uint32_t a = cur.node + 1, b = n.first;
    const double da = boxDistance(p, nodes_[a].lo, nodes_[a].hi), db = boxDistance(p, nodes_[b].lo, nodes_[b].hi);
    // Push the farther first so the nearer is searched first.
    if (da <= db) {
      if (db < best) stack[top++] = {b, db};
      if (da < best) stack[top++] = {a, da};
    } else {
      if (da < best) stack[top++] = {a, da};
      if (db < best) stack[top++] = {b, db};
    }
  }
  return best;
}

double measureSimplificationError(std::span<const glm::vec3> positions, std::span<const uint32_t> full,
                                  std::span<const uint32_t> simplified) {
  return measureSimplificationError(TriangleBvh(positions, full), positions, full, simplified);
}

double measureSimplificationError(const TriangleBvh& fullTree, std::span<const glm::vec3> positions,
                                  std::span<const uint32_t> full, std::span<const uint32_t> simplified) {
  if (simplified.empty()) return std::numeric_limits<double>::infinity();
  double error = 0.0;
  const TriangleBvh lodTree(positions, simplified);
  // A full-mesh vertex the level also uses lies on the level's surface (distance 0): only the others are searched.
  std::vector<char> seen(positions.size(), 0);
  for (uint32_t i : simplified) seen[i] = 1;
  // One budget for the whole measure (kErrorWorkPerQuery per query point); once spent, each remaining query takes
  // the first leaf it reaches, an upper bound of its distance, so the result bounds the exact error from above.
  uint64_t budget = kErrorWorkPerQuery * (uint64_t(full.size()) + uint64_t(simplified.size()) / 3 * 4);
  for (uint32_t i : full) {
    if (seen[i]) continue;
    seen[i] = 1;
    error = std::max(error, lodTree.distance(glm::dvec3(positions[i]), error, budget));
  }
  for (size_t t = 0; t + 2 < simplified.size(); t += 3) {
    glm::dvec3 a(positions[simplified[t]]), b(positions[simplified[t + 1]]), c(positions[simplified[t + 2]]);
    for (const glm::dvec3& s : {(a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5, (a + b + c) / 3.0})
      error = std::max(error, fullTree.distance(s, error, budget));
  }
  return error;
}

}  // namespace visbuf
