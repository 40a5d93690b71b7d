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

TriangleGrid::TriangleGrid(std::span<const glm::vec3> positions, std::span<const uint32_t> indices)
    : positions_(positions), indices_(indices) {
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (uint32_t i : indices) {
    lo = glm::min(lo, glm::dvec3(positions[i]));
    hi = glm::max(hi, glm::dvec3(positions[i]));
  }
  const size_t tris = indices.size() / 3;
  const glm::dvec3 ext = glm::max(hi - lo, glm::dvec3(1e-9));
  // About 2 triangles per cell for a surface: cells ~ tris^(1/2) per side of the largest extent.
  const double target = std::max(1.0, std::sqrt(double(tris)));
  cell_ = std::max({ext.x, ext.y, ext.z}) / target;
  dims_ = glm::max(glm::ivec3(glm::ceil(ext / cell_)), glm::ivec3(1));
  dims_ = glm::min(dims_, glm::ivec3(256));
  cell_ = std::max({ext.x / dims_.x, ext.y / dims_.y, ext.z / dims_.z}) * (1.0 + 1e-9);
  origin_ = lo;
  const size_t cells = size_t(dims_.x) * dims_.y * dims_.z;
  std::vector<uint32_t> counts(cells + 1, 0);
  auto forEachCell = [&](size_t t, auto&& fn) {
    glm::dvec3 a(positions[indices[3 * t]]), b(positions[indices[3 * t + 1]]), c(positions[indices[3 * t + 2]]);
    glm::ivec3 c0 = cellOf(glm::min(a, glm::min(b, c))), c1 = cellOf(glm::max(a, glm::max(b, c)));
    for (int z = c0.z; z <= c1.z; ++z)
      for (int y = c0.y; y <= c1.y; ++y)
        for (int x = c0.x; x <= c1.x; ++x) fn((size_t(z) * dims_.y + y) * dims_.x + x);
  };
  for (size_t t = 0; t < tris; ++t) forEachCell(t, [&](size_t c) { counts[c + 1]++; });
  for (size_t c = 0; c < cells; ++c) counts[c + 1] += counts[c];
  cellStart_ = counts;
  cellTris_.resize(counts[cells]);
  std::vector<uint32_t> fill(counts.begin(), counts.end() - 1);
  for (size_t t = 0; t < tris; ++t) forEachCell(t, [&](size_t c) { cellTris_[fill[c]++] = uint32_t(t); });
}

glm::ivec3 TriangleGrid::cellOf(const glm::dvec3& p) const {
  // Clamped in double before the conversion: a point far outside the grid (a simplified mesh's vertex on a
  // huge input, found by fuzz_gltf_import) gives a cell index beyond int, and converting it is undefined.
  const glm::dvec3 f = glm::floor((p - origin_) / cell_);
  glm::ivec3 c;
  for (int k = 0; k < 3; ++k) c[k] = f[k] >= 0.0 ? int(std::min(f[k], double(dims_[k] - 1))) : 0;  // NaN -> 0
  return c;
}

double TriangleGrid::distance(const glm::dvec3& p, double enough) const {
  // Search shells of cells around p's (clamped) cell until the nearest hit is closer than any
  // unvisited cell can be.
  const glm::ivec3 home = cellOf(p);
  // Distance from p to the grid box (p may lie outside it).
  const glm::dvec3 boxLo = origin_, boxHi = origin_ + glm::dvec3(dims_) * cell_;
  const double outside = glm::length(glm::max(glm::max(boxLo - p, p - boxHi), glm::dvec3(0.0)));
  double best = std::numeric_limits<double>::max();
  const int maxRing = std::max({dims_.x, dims_.y, dims_.z});
  for (int r = 0; r <= maxRing; ++r) {
    // Any triangle in a cell of ring r is at least (r - 1) cells away from p's home cell.
    if (best < outside + double(r - 1) * cell_) break;
    for (int z = home.z - r; z <= home.z + r; ++z)
      for (int y = home.y - r; y <= home.y + r; ++y)
        for (int x = home.x - r; x <= home.x + r; ++x) {
          if (std::max({std::abs(x - home.x), std::abs(y - home.y), std::abs(z - home.z)}) != r) continue;
          if (x < 0 || y < 0 || z < 0 || x >= dims_.x || y >= dims_.y || z >= dims_.z) continue;
          const size_t c = (size_t(z) * dims_.y + y) * dims_.x + x;
          for (uint32_t k = cellStart_[c]; k < cellStart_[c + 1]; ++k) {
            const uint32_t t = cellTris_[k];
            best = std::min(best, pointTriangleDistance(p, glm::dvec3(positions_[indices_[3 * t]]),
                                                        glm::dvec3(positions_[indices_[3 * t + 1]]),
                                                        glm::dvec3(positions_[indices_[3 * t + 2]])));
            if (best <= enough) return best;
          }
        }
  }
  return best;
}

double measureSimplificationError(std::span<const glm::vec3> positions, std::span<const uint32_t> full,
                                  std::span<const uint32_t> simplified) {
  return measureSimplificationError(TriangleGrid(positions, full), positions, full, simplified);
}

double measureSimplificationError(const TriangleGrid& fullGrid, std::span<const glm::vec3> positions,
                                  std::span<const uint32_t> full, std::span<const uint32_t> simplified) {
  if (simplified.empty()) return std::numeric_limits<double>::infinity();
  double error = 0.0;
  TriangleGrid lodGrid(positions, simplified);
  std::vector<char> seen(positions.size(), 0);
  for (uint32_t i : full) {
    if (seen[i]) continue;
    seen[i] = 1;
    error = std::max(error, lodGrid.distance(glm::dvec3(positions[i]), error));
  }
  for (size_t t = 0; t + 2 < simplified.size(); t += 3) {
    glm::dvec3 a(positions[simplified[t]]), b(positions[simplified[t + 1]]), c(positions[simplified[t + 2]]);
    for (const glm::dvec3& s : {(a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5, (a + b + c) / 3.0})
      error = std::max(error, fullGrid.distance(s, error));
  }
  return error;
}

}  // namespace visbuf
