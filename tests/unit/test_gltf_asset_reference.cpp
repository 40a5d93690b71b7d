// Shared assets imported by the engine against an independent reading of the same files: the test's own
// accessor reader (plain float VEC3 data, nlohmann::json + the .bin bytes) and its own arithmetic, or the same
// model stored another way (the glTF-Quantized copy against the float one).
//   - SimpleMorph: the mesh's default morph weights (0.5, 0.5) applied to POSITION;
//   - AnimatedMorphCube glTF-Quantized (KHR_mesh_quantization: uint16 positions, int8 normals, dequantised by
//     the node transform) against the float copy.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "asset/gltf_import.h"
#include "test_assets.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;

std::vector<uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Accessor `index` of a .gltf with external buffers, which must be a dense or strided FLOAT VEC3 without
// sparse data (the reference reader handles nothing else, so it cannot share the importer's decoding).
std::vector<glm::dvec3> readFloatVec3(const fs::path& gltf, const nlohmann::json& doc, int index) {
  const auto& acc = doc["accessors"][index];
  EXPECT_EQ(acc["componentType"].get<int>(), 5126);
  EXPECT_EQ(acc["type"].get<std::string>(), "VEC3");
  EXPECT_FALSE(acc.contains("sparse"));
  const auto& view = doc["bufferViews"][acc["bufferView"].get<int>()];
  const auto& buffer = doc["buffers"][view["buffer"].get<int>()];
  const std::vector<uint8_t> bytes = readBytes(gltf.parent_path() / buffer["uri"].get<std::string>());
  const size_t stride = view.value("byteStride", 12);
  const size_t start = view.value("byteOffset", 0) + acc.value("byteOffset", 0);
  std::vector<glm::dvec3> out;
  for (size_t i = 0; i < acc["count"].get<size_t>(); ++i) {
    float v[3];
    const size_t at = start + i * stride;
    if (at + sizeof v > bytes.size()) {
      ADD_FAILURE() << "accessor " << index << " runs past its buffer";
      return out;
    }
    std::memcpy(v, bytes.data() + at, sizeof v);
    out.push_back({v[0], v[1], v[2]});
  }
  return out;
}

TEST(GltfAssetReference, SimpleMorphDefaultWeightsApplied) {
  const fs::path file = test::assetPath("SimpleMorph/glTF/SimpleMorph.gltf");
  REQUIRE_ASSET(file);
  std::ifstream in(file);
  const nlohmann::json doc = nlohmann::json::parse(in);
  const auto& prim = doc["meshes"][0]["primitives"][0];
  const std::vector<double> weights = doc["meshes"][0]["weights"].get<std::vector<double>>();
  ASSERT_EQ(weights.size(), prim["targets"].size());
  ASSERT_FALSE(doc["nodes"][0].contains("weights")) << "the asset changed: the node now overrides the weights";
  ASSERT_FALSE(doc["nodes"][0].contains("matrix") || doc["nodes"][0].contains("translation") ||
               doc["nodes"][0].contains("rotation") || doc["nodes"][0].contains("scale"));
  const std::vector<glm::dvec3> base = readFloatVec3(file, doc, prim["attributes"]["POSITION"].get<int>());
  std::vector<glm::dvec3> expected = base;
  for (size_t t = 0; t < weights.size(); ++t) {
    const std::vector<glm::dvec3> delta = readFloatVec3(file, doc, prim["targets"][t]["POSITION"].get<int>());
    ASSERT_EQ(delta.size(), expected.size());
    for (size_t v = 0; v < expected.size(); ++v) expected[v] += weights[t] * delta[v];
  }
  bool anyMoved = false;  // the weights must actually move something, or the test could not fail
  for (size_t v = 0; v < expected.size(); ++v)
    anyMoved |= glm::length(expected[v] - base[v]) > 0.1;
  ASSERT_TRUE(anyMoved);

  auto mesh = importGltfMesh(file.string());
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  ASSERT_EQ(mesh->positions.size(), expected.size());
  // The triangle's vertices in file order (one primitive, no dedup in the importer): each within float rounding
  // of the double-precision reference (|p| <= 2, so 1e-6 is a few float ulps).
  for (size_t v = 0; v < expected.size(); ++v) {
    EXPECT_LE(glm::length(glm::dvec3(mesh->positions[v]) - expected[v]), 1e-6)
        << "vertex " << v << ": (" << mesh->positions[v].x << ", " << mesh->positions[v].y << ", "
        << mesh->positions[v].z << ") vs (" << expected[v].x << ", " << expected[v].y << ", " << expected[v].z << ")";
  }
}

// KHR_mesh_quantization on a real file: the quantised copy of AnimatedMorphCube, dequantised by its node
// transforms, against the float copy. The two files list vertices and triangles in different orders, so each
// float vertex is matched with the quantised vertex nearest to it among those with the same normal (within the
// normal bound), and each float triangle with a quantised triangle whose corners are the same points in the same
// cyclic order (same winding: front faces stay front faces).
// Bounds: positions within 1e-3 of the cube's 2-unit world size (2e-3; the uint16 step is 3.6e-4 here),
// normals (int8: a step of 1/127) within 0.02.
TEST(GltfAssetReference, AnimatedMorphCubeQuantizedMatchesFloat) {
  const fs::path floatFile = test::assetPath("AnimatedMorphCube/glTF/AnimatedMorphCube.gltf");
  const fs::path quantFile = test::assetPath("AnimatedMorphCube/glTF-Quantized/AnimatedMorphCube.gltf");
  REQUIRE_ASSET(floatFile);
  REQUIRE_ASSET(quantFile);
  auto f = importGltfMesh(floatFile.string());
  auto q = importGltfMesh(quantFile.string());
  ASSERT_TRUE(f.ok()) << f.error().message;
  ASSERT_TRUE(q.ok()) << q.error().message;
  ASSERT_EQ(f->positions.size(), q->positions.size());
  ASSERT_EQ(f->indices.size(), q->indices.size());
  constexpr double kPositionBound = 2e-3, kNormalBound = 0.02;
  double maxPosition = 0.0, maxNormal = 0.0;
  for (size_t v = 0; v < f->positions.size(); ++v) {
    double best = INFINITY, bestNormal = INFINITY;
    for (size_t w = 0; w < q->positions.size(); ++w) {
      const double n = glm::length(f->normals[v] - q->normals[w]);
      const double d = glm::length(f->positions[v] - q->positions[w]);
      if (n <= kNormalBound && d < best) best = d, bestNormal = n;
    }
    maxPosition = std::max(maxPosition, best);
    maxNormal = std::max(maxNormal, bestNormal);
  }
  size_t unmatched = 0;
  auto corner = [](const MeshSource& m, size_t t, size_t k) { return m.positions[m.indices[3 * t + k]]; };
  for (size_t t = 0; t < f->indices.size() / 3; ++t) {
    bool found = false;
    for (size_t u = 0; u < q->indices.size() / 3 && !found; ++u)
      for (size_t rot = 0; rot < 3 && !found; ++rot) {
        bool same = true;
        for (size_t k = 0; k < 3; ++k)
          same &= glm::length(corner(*f, t, k) - corner(*q, u, (k + rot) % 3)) <= kPositionBound;
        found = same;
      }
    unmatched += !found;
  }
  std::printf("AnimatedMorphCube quantised vs float: max position error %.3g, max normal error %.3g, %zu of %zu "
              "triangles without a same-winding match\n",
              maxPosition, maxNormal, unmatched, f->indices.size() / 3);
  EXPECT_LE(maxPosition, kPositionBound);
  EXPECT_LE(maxNormal, kNormalBound);
  EXPECT_EQ(unmatched, 0u);
}

}  // namespace
}  // namespace visbuf
