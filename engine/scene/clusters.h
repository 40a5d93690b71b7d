// Clusters of a LOD level (config.h CULL_CLUSTERS): runs of CLUSTER_TRIANGLES consecutive triangles, ordered by
// buildMesh so that each run is a tight meshlet, with the bounds the cull pass tests (gpu::ClusterData).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "visbuf/scene/scene.h"

namespace visbuf {

// Reorders the triangles indices[0, indexCount) (one LOD level) into meshlet order (meshopt_buildMeshlets,
// CLUSTER_TRIANGLES triangles each, with a weight on their normal cones). Every meshlet but the last has exactly
// CLUSTER_TRIANGLES triangles (its vertex limit, 3 per triangle, is never the one reached), so the runs the cull
// pass takes are the meshlets. Only the order changes: the same triangles, each with its winding. A level of at most
// CLUSTER_TRIANGLES triangles is left as it is.
// Bounded: meshopt_buildMeshlets is quadratic in a chunk's triangles on some meshes (a fan's centre vertex is
// rescanned for every triangle added; triangles sharing one centroid make its k-d tree one leaf scanned for every
// meshlet), so a level of more than kClusterChunkTriangles triangles is put in Morton order of its triangles'
// centroids and clustered in chunks of kClusterChunkTriangles consecutive triangles: O(indexCount *
// kClusterChunkTriangles) at worst, about linear on ordinary meshes; only the chunks' borders can split what one
// pass would have clustered together.
void clusterOrder(uint32_t* indices, size_t indexCount, const float* positions, size_t vertexCount, size_t stride);

inline constexpr size_t kClusterChunkTriangles = 4096;

// Bit i of x to bit 3i (x below 2^21): one coordinate spread out for a 63-bit Morton code (x | y << 1 | z << 2),
// the spatial orders of triangles (clusterOrder) and of objects (orderObjectsSpatially).
uint64_t spreadBits3(uint64_t x);

// Whether a LOD level is drawn as clusters (more than one cluster's triangles) and how many it has.
inline bool lodHasClusters(const Lod& lod) { return lod.indexCount / 3 > CLUSTER_TRIANGLES; }
inline uint32_t lodClusterCount(const Lod& lod) { return (lod.indexCount / 3 + CLUSTER_TRIANGLES - 1) / CLUSTER_TRIANGLES; }

// The bounds of the triangles indices[0, indexCount) (at most 512 triangles): a sphere that contains them
// (meshoptimizer's centre, the radius measured in double and padded so that the float sphere holds every vertex after
// rounding) and meshoptimizer's back-face cone (apex, axis, cutoff; cutoff 1: never back-facing).
gpu::ClusterData clusterBounds(const uint32_t* indices, size_t indexCount, const float* positions, size_t vertexCount,
                               size_t stride);

// The bounds of each cluster of mesh level `lod` (lodHasClusters), in order (clusterBounds).
std::vector<gpu::ClusterData> lodClusters(const Mesh& mesh, size_t lod);

}  // namespace visbuf
