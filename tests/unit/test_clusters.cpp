// Clusters (scene/clusters.h): the meshlet order keeps every triangle and its winding, the bounds hold every
// triangle, and the cull pass's cone test (the formula of cull.comp.glsl, with its margin) rejects a cluster only
// where every one of its triangles faces away from the camera, in double precision.
#include <algorithm>
#include <array>
#include <random>

#include <gtest/gtest.h>

#include "visbuf/scene/clusters.h"
#include "visbuf/scene/generate.h"
#include "triangle_sets.h"

using namespace visbuf;

using visbuf::test::sortedTriangles;

TEST(Clusters, MeshletOrderKeepsEveryTriangleAndItsWinding) {
  Result<Mesh> mesh = buildMesh(makeTorusKnot());
  ASSERT_TRUE(mesh.ok());
  const Lod& lod = mesh->lods[0];
  std::vector<uint32_t> shuffled(mesh->indices.begin() + lod.firstIndex,
                                 mesh->indices.begin() + lod.firstIndex + lod.indexCount);
  // Shuffle whole triangles, then order them again.
  std::vector<std::array<uint32_t, 3>> triangles;
  for (size_t i = 0; i < shuffled.size(); i += 3) triangles.push_back({shuffled[i], shuffled[i + 1], shuffled[i + 2]});
  std::shuffle(triangles.begin(), triangles.end(), std::mt19937(7));
  for (size_t t = 0; t < triangles.size(); ++t) std::copy(triangles[t].begin(), triangles[t].end(), shuffled.begin() + 3 * t);
  const std::vector<std::array<uint32_t, 3>> before = sortedTriangles(shuffled.data(), shuffled.size());
  clusterOrder(shuffled.data(), shuffled.size(), &mesh->vertices[0].px, mesh->vertices.size(), sizeof(gpu::Vertex));
  EXPECT_EQ(sortedTriangles(shuffled.data(), shuffled.size()), before);
  // The runs are tight again: the mean cluster radius is far below that of 64 triangles taken at random.
  Mesh ordered = *mesh, random = *mesh;
  std::copy(shuffled.begin(), shuffled.end(), ordered.indices.begin() + lod.firstIndex);
  for (size_t t = 0; t < triangles.size(); ++t)
    std::copy(triangles[t].begin(), triangles[t].end(), random.indices.begin() + lod.firstIndex + 3 * t);
  auto meanRadius = [](const Mesh& m) {
    double sum = 0.0;
    std::vector<gpu::ClusterData> c = lodClusters(m, 0);
    for (const gpu::ClusterData& d : c) sum += d.sphere.w;
    return sum / double(c.size());
  };
  EXPECT_LT(meanRadius(ordered), 0.25 * meanRadius(random));
}

TEST(Clusters, BoundsHoldTheirTrianglesAndConesRejectOnlyBackFaces) {
  Result<Mesh> mesh = buildMesh(makeTorusKnot());
  ASSERT_TRUE(mesh.ok());
  std::mt19937 rng(3);
  const glm::dvec3 centre(mesh->boundsSphere);
  const double reach = 3.0 * mesh->boundsSphere.w;
  std::uniform_real_distribution<double> u(-reach, reach);
  size_t tested = 0, rejected = 0, levels = 0;
  for (size_t l = 0; l < mesh->lods.size(); ++l) {
    const Lod& lod = mesh->lods[l];
    if (!lodHasClusters(lod)) continue;
    ++levels;
    const std::vector<gpu::ClusterData> clusters = lodClusters(*mesh, l);
    ASSERT_EQ(clusters.size(), lodClusterCount(lod));
    for (size_t c = 0; c < clusters.size(); ++c) {
      const gpu::ClusterData& d = clusters[c];
      const uint32_t first = lod.firstIndex + uint32_t(c) * 3 * CLUSTER_TRIANGLES;
      const uint32_t end = std::min(first + 3 * CLUSTER_TRIANGLES, lod.firstIndex + lod.indexCount);
      for (uint32_t i = first; i < end; ++i)
        ASSERT_LE(glm::length(glm::dvec3(mesh->position(mesh->indices[i])) - glm::dvec3(d.sphere)), double(d.sphere.w))
            << "level " << l << " cluster " << c;
      for (int e = 0; e < 64; ++e) {
        const glm::dvec3 eye = centre + glm::dvec3(u(rng), u(rng), u(rng));
        // cull.comp.glsl, in float as the shader computes it
        const glm::vec3 toApex = glm::vec3(d.apex) - glm::vec3(eye);
        const bool back = glm::dot(toApex, glm::vec3(d.cone)) >= (d.cone.w + 1e-3f) * glm::length(toApex);
        ++tested;
        if (!back) continue;
        ++rejected;
        for (uint32_t i = first; i < end; i += 3) {
          const glm::dvec3 a(mesh->position(mesh->indices[i])), b(mesh->position(mesh->indices[i + 1])),
              p(mesh->position(mesh->indices[i + 2]));
          const glm::dvec3 n = glm::cross(b - a, p - a);
          ASSERT_LT(glm::dot(n, eye - a), 0.0) << "level " << l << " cluster " << c << ": a front face rejected";
        }
      }
    }
  }
  std::printf("%zu levels with clusters; the cone test rejected %zu of %zu (cluster, camera) pairs\n", levels, rejected,
              tested);
  EXPECT_GE(levels, 3u);
  EXPECT_GT(rejected, tested / 10) << "the cones must reject a fair share of back-facing clusters";
}
