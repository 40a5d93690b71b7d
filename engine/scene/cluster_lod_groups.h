// Grouping of clusters for the cluster LOD build (cluster_lod.h): the graph of clusters sharing edges, cut into
// groups of about `groupSize` neighbouring clusters by METIS. Internal to the builder.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace visbuf::cluster_lod_detail {

// One cluster to group: its triangles (3 welded vertex ids each: equal positions have equal ids) and its centre.
struct GroupInput {
  std::span<const uint32_t> weldedIndices;
  glm::vec3 centre{0.0f};
};

// Partitions the clusters into groups of about groupSize (>= 2) clusters, each group as positions into `clusters`,
// every cluster in exactly one group, no group empty. Neighbours (clusters sharing edges, weighted by how many) go
// together: METIS k-way on chunks of at most kGroupChunkClusters clusters consecutive along a Morton curve of the
// centres (METIS's cost grows with the part count; a chunk keeps each call small and the whole about linear), vertex
// weights the triangle counts. Where METIS fails, the chunk is cut into runs of groupSize along the curve.
// Deterministic (METIS with a fixed seed).
std::vector<std::vector<uint32_t>> groupClusters(std::span<const GroupInput> clusters, uint32_t groupSize);

inline constexpr uint32_t kGroupChunkClusters = 2048;

}  // namespace visbuf::cluster_lod_detail
