// uploadScene's bounded staging: the geometry pools go to the GPU in chunks through one reused staging buffer
// that is smaller than the data. Read back, they equal the CPU concatenation of the meshes byte for byte.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "gpu_test_util.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/scene/generate.h"
#include "visbuf/scene/gpu_scene.h"

namespace visbuf {
namespace {

template <typename T>
std::vector<uint8_t> bytesOf(const std::vector<T>& v) {
  std::vector<uint8_t> out(v.size() * sizeof(T));
  if (!v.empty()) std::memcpy(out.data(), v.data(), out.size());
  return out;
}

GPU_TEST(SceneUpload, ChunkedPoolsEqualTheMeshesByteForByte) {
  Scene scene;
  for (uint32_t i = 0; i < 6; ++i) {
    Result<Mesh> mesh = buildMesh(makeTorusKnot(96 + 32 * i, 12 + 2 * i));
    ASSERT_TRUE(mesh) << mesh.error().message;
    if (i % 2 == 1) {  // extra streams on some meshes: the extras pool has gaps to place correctly
      for (size_t v = 0; v < mesh->vertices.size(); ++v) {
        mesh->tangents.push_back(glm::vec4(v % 3 == 0 ? 0.0f : 1.0f, v % 3 == 0 ? 1.0f : 0.0f, 0.0f, v % 2 ? 1.0f : -1.0f));
        mesh->uvs1.push_back(glm::vec2(float(v), -float(i)));
      }
    }
    scene.meshes.push_back(std::move(mesh.value()));
    scene.objects.push_back({glm::translate(glm::dmat4(1.0), glm::dvec3(3.0 * i, 0.0, 0.0)), i, 0});
  }
  scene.materials.push_back(Material{});
  Result<GpuScene> g = uploadScene(dev, scene);
  ASSERT_TRUE(g) << g.error().message;

  std::vector<gpu::Vertex> vertices;
  std::vector<uint32_t> indices;
  std::vector<gpu::VertexExtra> extras;
  for (const Mesh& m : scene.meshes) {
    vertices.insert(vertices.end(), m.vertices.begin(), m.vertices.end());
    indices.insert(indices.end(), m.indices.begin(), m.indices.end());
    for (size_t v = 0; !m.tangents.empty() && v < m.vertices.size(); ++v) {
      gpu::VertexExtra e{};
      if (m.tangents[v].w != 0.0f) {
        e.tangent = octEncode(glm::normalize(glm::vec3(m.tangents[v])));
        e.tangentW = m.tangents[v].w < 0.0f ? -1.0f : 1.0f;
      }
      e.u1 = m.uvs1[v].x;
      e.v1 = m.uvs1[v].y;
      extras.push_back(e);
    }
  }
  // The staging buffer is smaller than the pools: the upload really went in several chunks.
  ASSERT_LT(g->stagingBytes, vertices.size() * sizeof(gpu::Vertex));
  EXPECT_LE(g->stagingBytes, uint64_t{8} << 20);
  EXPECT_GE(g->uploadHostBytes, g->stagingBytes);
  const std::vector<uint8_t> v = bytesOf(vertices), i = bytesOf(indices), e = bytesOf(extras);
  EXPECT_TRUE(gpu::downloadBuffer(dev, g->vertices, 0, v.size()) == v) << "vertex pool";
  EXPECT_TRUE(gpu::downloadBuffer(dev, g->indices, 0, i.size()) == i) << "index pool";
  EXPECT_TRUE(gpu::downloadBuffer(dev, g->vertexExtras, 0, e.size()) == e) << "extras pool";
  // Each mesh's table entry points at its own data.
  uint32_t vertexOffset = 0, indexOffset = 0;
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    EXPECT_EQ(g->meshTable[m].vertexOffset, vertexOffset);
    EXPECT_EQ(g->meshTable[m].lods[0].firstIndex, indexOffset);
    vertexOffset += uint32_t(scene.meshes[m].vertices.size());
    indexOffset += uint32_t(scene.meshes[m].indices.size());
  }
}

}  // namespace
}  // namespace visbuf
