// Measured geometric error between two triangle meshes: a two-sided, sampled Hausdorff distance.
// Used to record each LOD level's error in object-space units, because meshoptimizer's own estimate
// (especially meshopt_simplifySloppy's) can be far below the real deviation of the silhouette.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace visbuf {

// A uniform grid over a mesh's triangles answering "distance from a point to the nearest triangle".
class TriangleGrid {
 public:
  TriangleGrid(std::span<const glm::vec3> positions, std::span<const uint32_t> indices);
  // Exact distance to the nearest triangle (double precision point-triangle distance). With `enough`, the search
  // may stop at any triangle within that distance and return its distance (still an upper bound of the nearest
  // at most `enough`): a maximum over many points needs no more.
  double distance(const glm::dvec3& p, double enough = -1.0) const;

 private:
  glm::ivec3 cellOf(const glm::dvec3& p) const;
  std::span<const glm::vec3> positions_;
  std::span<const uint32_t> indices_;
  glm::dvec3 origin_{0.0};
  double cell_ = 1.0;
  glm::ivec3 dims_{1};
  std::vector<uint32_t> cellStart_;  // CSR: triangles of cell c are cellTris_[cellStart_[c] .. cellStart_[c+1])
  std::vector<uint32_t> cellTris_;
};

// Distance from point p to triangle (a, b, c) (Ericson, "Real-Time Collision Detection", 5.1.5).
double pointTriangleDistance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);

// Two-sided error between the full mesh and a simplified one sharing its vertex array: the largest
// distance from any full-mesh vertex to the simplified surface, and from samples of every simplified
// triangle (vertices, edge midpoints, centroid) to the full surface.
double measureSimplificationError(std::span<const glm::vec3> positions, std::span<const uint32_t> full,
                                  std::span<const uint32_t> simplified);
// The same with the full mesh's grid built once (TriangleGrid(positions, full)), for many levels of one mesh.
double measureSimplificationError(const TriangleGrid& fullGrid, std::span<const glm::vec3> positions,
                                  std::span<const uint32_t> full, std::span<const uint32_t> simplified);

}  // namespace visbuf
