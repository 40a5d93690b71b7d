// Measured geometric error between two triangle meshes: a two-sided, sampled Hausdorff distance.
// Used to record each LOD level's error in object-space units, because meshoptimizer's own estimate
// (especially meshopt_simplifySloppy's) can be far below the real deviation of the silhouette.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace visbuf {

// A bounding-volume hierarchy over a mesh's triangles answering "distance from a point to the nearest triangle".
// Build: O(n log n) time and O(n) memory for n triangles whatever their shapes (median splits on the longest axis
// of the centroids' box: every split halves its triangles, so the depth is at most log2(n) + 1 even when every
// triangle is the same one). The spans must outlive the tree; every index must be < positions.size().
class TriangleBvh {
 public:
  TriangleBvh(std::span<const glm::vec3> positions, std::span<const uint32_t> indices);
  // Exact distance to the nearest triangle (double precision point-triangle distance; max double when there is
  // none). With `enough`, the search may stop at any triangle within that distance and return its distance (still
  // an upper bound of the nearest at most `enough`): a maximum over many points needs no more.
  double distance(const glm::dvec3& p, double enough = -1.0) const;
  // The same with a work budget, in nodes and triangles visited, taken from `budget`. When the budget runs out the
  // search returns the nearest triangle found so far: an UPPER bound of the exact distance, never below it. With
  // budget 0 it still descends to one leaf (at most depth + 4 visits), so the result is finite whenever there are
  // triangles.
  double distance(const glm::dvec3& p, double enough, uint64_t& budget) const;
  size_t triangleCount() const { return indices_.size() / 3; }

 private:
  struct Node {
    glm::vec3 lo, hi;     // bounds of the node's triangles (float positions: min / max are exact)
    uint32_t first = 0;   // leaf: first slot in order_; inner: index of the second child (the first is next)
    uint32_t count = 0;   // leaf: triangle count (> 0); inner: 0
  };
  double search(const glm::dvec3& p, double enough, uint64_t* budget) const;
  uint32_t build(uint32_t first, uint32_t count, std::vector<glm::vec3>& centroid);
  std::span<const glm::vec3> positions_;
  std::span<const uint32_t> indices_;
  std::vector<Node> nodes_;        // depth-first: a node's first child follows it
  std::vector<uint32_t> order_;    // triangle numbers, leaves' triangles contiguous
};

// Distance from point p to triangle (a, b, c) (Ericson, "Real-Time Collision Detection", 5.1.5).
double pointTriangleDistance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);

// Two-sided error between the full mesh and a simplified one sharing its vertex array: the largest
// distance from any full-mesh vertex to the simplified surface, and from samples of every simplified
// triangle (vertices, edge midpoints, centroid) to the full surface.
// Bounded work: the nearest-triangle searches together visit at most kErrorWorkPerQuery nodes and triangles per
// query point (plus one descent each once that is spent), so adversarial meshes (thousands of coincident or
// overlapping triangles, long slivers, fans, huge triangles among small ones) cannot make the measure quadratic.
// Where the budget runs out the result is an upper bound of the exact error (a LOD level is then drawn closer
// than it could be, never farther); ordinary meshes stay far below the budget and get the exact figure.
double measureSimplificationError(std::span<const glm::vec3> positions, std::span<const uint32_t> full,
                                  std::span<const uint32_t> simplified);
// The same with the full mesh's tree built once (TriangleBvh(positions, full)), for many levels of one mesh.
double measureSimplificationError(const TriangleBvh& fullTree, std::span<const glm::vec3> positions,
                                  std::span<const uint32_t> full, std::span<const uint32_t> simplified);
// The work budget above, per query point (a query of an ordinary mesh visits tens of nodes).
inline constexpr uint64_t kErrorWorkPerQuery = 16;

}  // namespace visbuf
