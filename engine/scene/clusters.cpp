#include "visbuf/scene/clusters.h"

#include <algorithm>

#include <meshoptimizer.h>

namespace visbuf {

void clusterOrder(uint32_t* indices, size_t indexCount, const float* positions, size_t vertexCount, size_t stride) {
  if (indexCount / 3 <= CLUSTER_TRIANGLES) return;
  constexpr size_t kMaxVertices = 3 * CLUSTER_TRIANGLES;
  static_assert(kMaxVertices <= 255, "meshopt_buildMeshlets takes at most 255 vertices per meshlet");
  const size_t bound = meshopt_buildMeshletsBound(indexCount, kMaxVertices, CLUSTER_TRIANGLES);
  std::vector<meshopt_Meshlet> meshlets(bound);
  std::vector<uint32_t> meshletVertices(bound * kMaxVertices);
  std::vector<unsigned char> meshletTriangles(bound * CLUSTER_TRIANGLES * 3);
  const size_t count = meshopt_buildMeshlets(meshlets.data(), meshletVertices.data(), meshletTriangles.data(), indices,
                                             indexCount, positions, vertexCount, stride, kMaxVertices,
                                             CLUSTER_TRIANGLES, 0.5f);
  std::vector<uint32_t> ordered;
  ordered.reserve(indexCount);
  for (size_t m = 0; m < count; ++m) {
    const meshopt_Meshlet& ml = meshlets[m];
    for (uint32_t k = 0; k < ml.triangle_count * 3; ++k)
      ordered.push_back(meshletVertices[ml.vertex_offset + meshletTriangles[ml.triangle_offset + k]]);
  }
  if (ordered.size() == indexCount) std::copy(ordered.begin(), ordered.end(), indices);
}

std::vector<gpu::ClusterData> lodClusters(const Mesh& mesh, size_t lod) {
  std::vector<gpu::ClusterData> out;
  const Lod& l = mesh.lods[lod];
  if (!lodHasClusters(l)) return out;
  const uint32_t* indices = mesh.indices.data() + l.firstIndex;
  for (uint32_t first = 0; first < l.indexCount; first += 3 * CLUSTER_TRIANGLES) {
    const uint32_t n = std::min(l.indexCount - first, 3 * CLUSTER_TRIANGLES);
    const meshopt_Bounds b = meshopt_computeClusterBounds(indices + first, n, &mesh.vertices[0].px,
                                                          mesh.vertices.size(), sizeof(gpu::Vertex));
    const glm::dvec3 c(b.center[0], b.center[1], b.center[2]);
    double r = 0.0;
    for (uint32_t i = 0; i < n; ++i) r = std::max(r, glm::length(glm::dvec3(mesh.position(indices[first + i])) - c));
    gpu::ClusterData d;
    d.sphere = glm::vec4(glm::vec3(c), float(r * (1.0 + 1e-5) + 1e-6));
    d.cone = glm::vec4(b.cone_axis[0], b.cone_axis[1], b.cone_axis[2], b.cone_cutoff);
    d.apex = glm::vec4(b.cone_apex[0], b.cone_apex[1], b.cone_apex[2], 0.0f);
    out.push_back(d);
  }
  return out;
}

}  // namespace visbuf
