// Triangles compared as sets, whatever their order in an index list (the meshlet orders and the cluster LOD cut).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace visbuf::test {

// A triangle as its three indices rotated so that the smallest comes first (the winding kept).
inline std::array<uint32_t, 3> canonicalTriangle(const uint32_t* t) {
  const int k = t[0] <= t[1] && t[0] <= t[2] ? 0 : t[1] <= t[2] ? 1 : 2;
  return {t[k], t[(k + 1) % 3], t[(k + 2) % 3]};
}

// The triangles of indices[0, count), canonical, sorted.
inline std::vector<std::array<uint32_t, 3>> sortedTriangles(const uint32_t* indices, size_t count) {
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t i = 0; i + 2 < count; i += 3) out.push_back(canonicalTriangle(indices + i));
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace visbuf::test
