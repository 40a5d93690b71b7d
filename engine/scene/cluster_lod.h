// A cluster LOD hierarchy (a DAG of cluster groups, the Nanite / meshoptimizer "clusterlod" scheme) built at bake
// time from one indexed triangle mesh, and the CPU reference of its per-cluster selection.
//
// Build: the mesh's triangles are split into clusters of at most CLUSTER_TRIANGLES triangles (meshopt_buildMeshlets,
// level 0: exactly the input triangles). Each round groups neighbouring clusters (METIS on the graph of clusters
// sharing edges, weighted by the shared edge count), merges each group, simplifies it to about half its triangles
// with its border locked (meshopt_SimplifyLockBorder: the vertices on the group's outline keep their place and
// index), and splits the result into new clusters. Groups whose simplification does not reduce them (their border
// holds most of their vertices) keep their clusters for the next round's grouping. The rounds end when one cluster
// is left, a round simplifies no group, or kClusterLodMaxLevels rounds have run; the clusters left are the roots.
//
// Selection (per cluster, no traversal): with projectedError() of a (sphere, error) pair, a cluster is drawn when
//   projectedError(self) <= threshold < projectedError(parent).
// Every cluster made by one group has that group's (sphere, error) as its `self`; every cluster merged into a group
// has the group's as its `parent`; errors and spheres only grow up the DAG (a group's error >= its children's,
// its sphere contains theirs), so along every chain of groups exactly one level passes the test and the clusters
// drawn cover the surface once. Locked group borders make neighbouring choices share their edges: no cracks.
// Known limit (meshoptimizer 0.18 locks every border vertex): the mesh's own open border (a terrain's outline) is
// a border of every group that touches it, so it is never simplified.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/core/result.h"
#include "visbuf/shared/types.h"

namespace visbuf {

// The rounds of simplification at most (each halves the triangles of the groups it simplifies: 32 rounds take
// 2^32 triangles to one cluster), so hostile input cannot loop.
inline constexpr uint32_t kClusterLodMaxLevels = 32;

// A sphere and the error of the surface it bounds: `error` in object-space units, an upper bound of the distance
// between this surface and the input mesh's (sampled: measureSimplificationError of each simplification, summed
// along the chain); 0 for the input triangles.
struct ClusterLodBounds {
  glm::vec4 sphere{0.0f};  // centre xyz, radius w (object space)
  float error = 0.0f;
};

struct ClusterLodCluster {
  uint32_t firstIndex = 0;     // into ClusterLod::indices
  uint32_t triangleCount = 0;  // 1..CLUSTER_TRIANGLES
  uint32_t level = 0;          // rounds of simplification behind it: 0 = the input triangles
  glm::vec4 sphere{0.0f};      // contains the cluster's triangles (culling)
  ClusterLodBounds self;       // level 0: its own sphere and error 0; else the group that made it
  ClusterLodBounds parent;     // the group it was merged into; error +infinity for a root (never replaced)
  uint32_t group = ~0u;        // index of that group in ClusterLod::groups; ~0u for a root
  uint32_t sourceGroup = ~0u;  // index of the group that made it; ~0u at level 0
};

// A group of clusters merged and simplified together: its bounds are the `parent` of each cluster merged into it
// and the `self` of each cluster it made.
struct ClusterLodGroup {
  ClusterLodBounds bounds;
  uint32_t level = 0;  // the round that simplified it: the clusters it made have level + 1
};

struct ClusterLod {
  std::vector<uint32_t> indices;  // every cluster's triangles; indices into the input's vertices
  std::vector<ClusterLodCluster> clusters;
  std::vector<ClusterLodGroup> groups;
  uint32_t levels = 0;  // the highest cluster level + 1
};

struct ClusterLodOptions {
  uint32_t groupSize = 4;      // clusters per group METIS aims at (>= 2)
  float simplifyRatio = 0.5f;  // a group is simplified to this fraction of its triangles
  float minReduction = 0.85f;  // a simplification keeping more than this fraction of them makes no progress
  // Level 0 is the input's runs of CLUSTER_TRIANGLES consecutive triangles as given (the last one shorter), not
  // reordered: for a level already in meshlet order (buildMesh's lods[0]), level-0 cluster k is then the cull pass's
  // cluster k, the same triangles at the same index positions (the IDs of a cut pinned to level 0 are --lod off's).
  bool inputInClusterOrder = false;
};

// Builds the hierarchy of the mesh positions[0 .. vertexCount) (`stride` bytes apart, 3 floats each) and
// indices[0 .. indexCount). Fails with MalformedInput for an index count that is not a multiple of 3 or is 0, an
// index out of range or a non-finite position, and CapacityExceeded beyond 2^32 - 1 indices in all. Degenerate
// and duplicate triangles are clustered like any other (buildMesh drops them before); the hierarchy's crack-free
// property holds for manifold input. Deterministic. Work about O(n log n) for n triangles; memory a few times the
// input's indices.
Result<ClusterLod> buildClusterLod(const float* positions, size_t vertexCount, size_t stride, const uint32_t* indices,
                                   size_t indexCount, const ClusterLodOptions& options = {});

// A view for the selection, in the mesh's object space (a uniformly scaled instance: the camera brought into object
// space and the projection scale multiplied by the instance's scale).
struct ClusterLodView {
  glm::vec3 camera{0.0f};
  // Pixels per object-space unit at distance 1: viewport height / (2 tan(fovY / 2)) for a perspective camera; > 0.
  float projectionScale = 1.0f;
  float thresholdPixels = 1.0f;  // >= 0; 0 draws the input triangles (level 0) everywhere
  float minDistance = 1e-4f;     // distances below this (a camera inside a sphere) count as this; > 0
};

// The projected size in pixels of `bounds.error` seen from the view: error * projectionScale / d, d the distance
// from the camera to the sphere's surface (at least minDistance). Monotonic: a larger error or a sphere containing
// another never projects smaller. float arithmetic, so that a GPU evaluating the same expression agrees.
float projectedError(const ClusterLodBounds& bounds, const ClusterLodView& view);

// The clusters drawn from the view (indices into lod.clusters, in order): projectedError(self) <= threshold <
// projectedError(parent), each decided on its own.
std::vector<uint32_t> selectClusters(const ClusterLod& lod, const ClusterLodView& view);

}  // namespace visbuf
