#include "visbuf/scene/clusters.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <meshoptimizer.h>

namespace visbuf {

uint64_t spreadBits3(uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

void clusterOrder(uint32_t* indices, size_t indexCount, const float* positions, size_t vertexCount, size_t stride) {
  if (indexCount / 3 <= CLUSTER_TRIANGLES) return;
  constexpr size_t kMaxVertices = 3 * CLUSTER_TRIANGLES;
  static_assert(kMaxVertices <= 255, "meshopt_buildMeshlets takes at most 255 vertices per meshlet");
  static_assert(kClusterChunkTriangles % CLUSTER_TRIANGLES == 0, "every chunk's meshlets are full but the level's last");
  const size_t floatStride = stride / sizeof(float);
  const size_t chunkIndices = 3 * kClusterChunkTriangles;
  const size_t bound = meshopt_buildMeshletsBound(std::min(indexCount, chunkIndices), kMaxVertices, CLUSTER_TRIANGLES);
  std::vector<meshopt_Meshlet> meshlets(bound);
  std::vector<uint32_t> meshletVertices(bound * kMaxVertices);
  std::vector<unsigned char> meshletTriangles(bound * CLUSTER_TRIANGLES * 3);
  // Each chunk is clustered on its own vertices only (local numbering), so a chunk's cost does not grow with the
  // mesh's vertex count.
  std::vector<uint32_t> localOf(vertexCount, ~0u);
  std::vector<uint32_t> globalOf, local;
  std::vector<float> localPositions;
  // More than one chunk: the triangles first go in Morton order of their centroids (over the level's box), so each
  // chunk is a compact region whatever the input order. O(n log n).
  std::vector<uint32_t> spatial;
  if (indexCount > chunkIndices) {
    const size_t tris = indexCount / 3;
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    auto at = [&](uint32_t v) { return glm::vec3(positions[v * floatStride], positions[v * floatStride + 1],
                                                 positions[v * floatStride + 2]); };
    for (size_t k = 0; k < indexCount; ++k) {
      lo = glm::min(lo, at(indices[k]));
      hi = glm::max(hi, at(indices[k]));
    }
    const glm::dvec3 scale = 2097151.0 / glm::max(glm::dvec3(hi) - glm::dvec3(lo), glm::dvec3(1e-30));
    std::vector<std::pair<uint64_t, uint32_t>> keys(tris);
    for (size_t t = 0; t < tris; ++t) {
      const glm::dvec3 c = (glm::dvec3(at(indices[3 * t])) + glm::dvec3(at(indices[3 * t + 1])) +
                            glm::dvec3(at(indices[3 * t + 2]))) / 3.0;
      const glm::dvec3 q = glm::clamp((c - glm::dvec3(lo)) * scale, glm::dvec3(0.0), glm::dvec3(2097151.0));
      const uint64_t code = spreadBits3(uint64_t(q.x)) | spreadBits3(uint64_t(q.y)) << 1 | spreadBits3(uint64_t(q.z)) << 2;
      keys[t] = {code, uint32_t(t)};
    }
    std::sort(keys.begin(), keys.end());
    spatial.resize(indexCount);
    for (size_t t = 0; t < tris; ++t) std::copy_n(indices + 3 * size_t(keys[t].second), 3, spatial.begin() + 3 * t);
  }
  const uint32_t* source = spatial.empty() ? indices : spatial.data();
  std::vector<uint32_t> ordered;
  ordered.reserve(indexCount);
  for (size_t first = 0; first < indexCount; first += chunkIndices) {
    const size_t n = std::min(chunkIndices, indexCount - first);
    globalOf.clear();
    local.resize(n);
    localPositions.clear();
    for (size_t k = 0; k < n; ++k) {
      const uint32_t v = source[first + k];
      if (localOf[v] == ~0u) {
        localOf[v] = uint32_t(globalOf.size());
        globalOf.push_back(v);
        localPositions.insert(localPositions.end(), positions + v * floatStride, positions + v * floatStride + 3);
      }
      local[k] = localOf[v];
    }
    for (uint32_t v : globalOf) localOf[v] = ~0u;
    const size_t count = meshopt_buildMeshlets(meshlets.data(), meshletVertices.data(), meshletTriangles.data(),
                                               local.data(), n, localPositions.data(), globalOf.size(),
                                               3 * sizeof(float), kMaxVertices, CLUSTER_TRIANGLES, 0.5f);
    for (size_t m = 0; m < count; ++m) {
      const meshopt_Meshlet& ml = meshlets[m];
      for (uint32_t k = 0; k < ml.triangle_count * 3; ++k)
        ordered.push_back(globalOf[meshletVertices[ml.vertex_offset + meshletTriangles[ml.triangle_offset + k]]]);
    }
  }
  if (ordered.size() == indexCount) std::copy(ordered.begin(), ordered.end(), indices);
}

gpu::ClusterData clusterBounds(const uint32_t* indices, size_t indexCount, const float* positions, size_t vertexCount,
                               size_t stride) {
  const meshopt_Bounds b = meshopt_computeClusterBounds(indices, indexCount, positions, vertexCount, stride);
  const glm::dvec3 c(b.center[0], b.center[1], b.center[2]);
  const size_t floatStride = stride / sizeof(float);
  double r = 0.0;
  for (size_t i = 0; i < indexCount; ++i) {
    const float* p = positions + indices[i] * floatStride;
    r = std::max(r, glm::length(glm::dvec3(p[0], p[1], p[2]) - c));
  }
  gpu::ClusterData d;
  d.sphere = glm::vec4(glm::vec3(c), float(r * (1.0 + 1e-5) + 1e-6));
  d.cone = glm::vec4(b.cone_axis[0], b.cone_axis[1], b.cone_axis[2], b.cone_cutoff);
  d.apex = glm::vec4(b.cone_apex[0], b.cone_apex[1], b.cone_apex[2], 0.0f);
  return d;
}

std::vector<gpu::ClusterData> lodClusters(const Mesh& mesh, size_t lod) {
  std::vector<gpu::ClusterData> out;
  const Lod& l = mesh.lods[lod];
  if (!lodHasClusters(l)) return out;
  const uint32_t* indices = mesh.indices.data() + l.firstIndex;
  for (uint32_t first = 0; first < l.indexCount; first += 3 * CLUSTER_TRIANGLES)
    out.push_back(clusterBounds(indices + first, std::min(l.indexCount - first, 3 * CLUSTER_TRIANGLES),
                                &mesh.vertices[0].px, mesh.vertices.size(), sizeof(gpu::Vertex)));
  return out;
}

}  // namespace visbuf
