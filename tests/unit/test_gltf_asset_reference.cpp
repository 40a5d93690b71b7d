// Shared assets imported by the engine against an independent reading of the same files: the test's own
// accessor reader (plain float VEC3 data, nlohmann::json + the .bin bytes) and its own arithmetic, or the same
// model stored another way (the glTF-Quantized copy against the float one).
//   - SimpleMorph: the mesh's default morph weights (0.5, 0.5) applied to POSITION; and, as a scene whose weights a
//     clip animates, its base shape and both targets' deltas kept (import, then welding and the LOD chain);
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

#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "temp_dir_test.h"
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

// SimpleMorph as a scene: its node's weights are animated, so the importer keeps the targets instead of baking
// them. The base positions and both targets' POSITION deltas, read independently from simpleMorphGeometry.bin,
// must come out exactly (float data copied, no arithmetic), the default weights beside them; after buildMesh
// (welding, fetch reordering, LOD chain) every vertex must still carry its own deltas: each built vertex is
// matched to the file vertex at the same base position and its deltas compared.
TEST(GltfAssetReference, SimpleMorphSceneKeepsItsDeltas) {
  const fs::path file = test::assetPath("SimpleMorph/glTF/SimpleMorph.gltf");
  REQUIRE_ASSET(file);
  std::ifstream in(file);
  const nlohmann::json doc = nlohmann::json::parse(in);
  const auto& prim = doc["meshes"][0]["primitives"][0];
  ASSERT_EQ(doc["animations"][0]["channels"][0]["target"]["path"].get<std::string>(), "weights");
  const std::vector<double> weights = doc["meshes"][0]["weights"].get<std::vector<double>>();
  const std::vector<glm::dvec3> base = readFloatVec3(file, doc, prim["attributes"]["POSITION"].get<int>());
  std::vector<std::vector<glm::dvec3>> deltas;
  for (size_t t = 0; t < prim["targets"].size(); ++t)
    deltas.push_back(readFloatVec3(file, doc, prim["targets"][t]["POSITION"].get<int>()));
  ASSERT_EQ(deltas.size(), 2u);
  double largest = 0.0;  // the deltas must move something, or matching them could not fail
  for (const auto& d : deltas)
    for (const glm::dvec3& x : d) largest = std::max(largest, glm::length(x));
  ASSERT_GT(largest, 0.5);

  auto imported = importGltfScene(file.string());
  ASSERT_TRUE(imported.ok()) << imported.error().message;
  ASSERT_EQ(imported->meshes.size(), 1u);
  ASSERT_EQ(imported->instances.size(), 1u);
  const MeshSource& src = imported->meshes[0].source;
  EXPECT_TRUE(imported->instances[0].morphed);
  ASSERT_EQ(src.positions.size(), base.size());
  ASSERT_EQ(src.morphTargets.size(), deltas.size());
  ASSERT_EQ(src.morphWeights.size(), weights.size());
  for (size_t t = 0; t < weights.size(); ++t) EXPECT_EQ(double(src.morphWeights[t]), double(float(weights[t])));
  for (size_t v = 0; v < base.size(); ++v) {
    EXPECT_EQ(glm::dvec3(src.positions[v]), base[v]) << "vertex " << v << ": weights baked into the base shape?";
    for (size_t t = 0; t < deltas.size(); ++t) {
      ASSERT_EQ(src.morphTargets[t].positions.size(), base.size());
      EXPECT_EQ(glm::dvec3(src.morphTargets[t].positions[v]), deltas[t][v]) << "target " << t << " vertex " << v;
      EXPECT_TRUE(src.morphTargets[t].tangents.empty());  // the file has no TANGENT targets
    }
  }
  // The morph-only node is skinned by a one-joint skin at the node itself.
  ASSERT_EQ(imported->instances[0].skin, 0);
  ASSERT_EQ(imported->skins.size(), 1u);
  EXPECT_EQ(imported->skins[0].joints, std::vector<uint32_t>{uint32_t(imported->instances[0].node)});
  EXPECT_EQ(imported->skins[0].inverseBindMatrices[0], glm::dmat4(1.0));

  auto scene = buildImportedScene(*imported, MeshBuildOptions{});
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  ASSERT_EQ(scene->skinnedObjects.size(), 1u);
  EXPECT_EQ(scene->skinnedObjects[0].morphNode, imported->instances[0].node);
  const Mesh& mesh = scene->meshes[0];
  ASSERT_EQ(mesh.morphTargetCount, deltas.size());
  ASSERT_EQ(mesh.morphDeltas.size(), deltas.size() * mesh.vertices.size());
  for (uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    size_t match = base.size();
    for (size_t w = 0; w < base.size(); ++w)
      if (glm::dvec3(mesh.position(v)) == base[w]) match = w;
    ASSERT_LT(match, base.size()) << "built vertex " << v << " is at no file position";
    for (size_t t = 0; t < deltas.size(); ++t) {
      const gpu::MorphDelta& d = mesh.morphDeltas[t * mesh.vertices.size() + v];
      EXPECT_EQ(glm::dvec3(d.px, d.py, d.pz), deltas[t][match]) << "target " << t << " built vertex " << v;
    }
    // And the reference morph at the default weights is the baked import's position.
    const MorphedVertex m = morphVertex(mesh, v, weights);
    glm::dvec3 expected = base[match];
    for (size_t t = 0; t < deltas.size(); ++t) expected += weights[t] * deltas[t][match];
    EXPECT_LE(glm::length(m.position - expected), 1e-12);
  }
}

// The other side of the rule: SimpleMorph without its animation (a copy of the .gltf with "animations" removed,
// the .bin files beside it) has no weights channel, so its default weights are baked into the vertices as
// before: no morph targets kept, no skin made up, no skinned object (so the renderer records no skinning).
class GltfAssetReferenceFiles : public test::TempDirTest {};
TEST_F(GltfAssetReferenceFiles, SimpleMorphWithoutAnimationIsBakedAndStatic) {
  const fs::path file = test::assetPath("SimpleMorph/glTF/SimpleMorph.gltf");
  REQUIRE_ASSET(file);
  std::ifstream in(file);
  nlohmann::json doc = nlohmann::json::parse(in);
  ASSERT_TRUE(doc.contains("animations"));
  doc.erase("animations");
  for (const auto& entry : fs::directory_iterator(file.parent_path()))
    if (entry.path().extension() == ".bin") fs::copy_file(entry.path(), dir_ / entry.path().filename());
  const fs::path copy = dir_ / "SimpleMorphStill.gltf";
  std::ofstream(copy) << doc.dump();
  auto imported = importGltfScene(copy.string());
  ASSERT_TRUE(imported.ok()) << imported.error().message;
  ASSERT_EQ(imported->meshes.size(), 1u);
  EXPECT_TRUE(imported->meshes[0].source.morphTargets.empty());
  EXPECT_TRUE(imported->meshes[0].source.joints.empty());
  EXPECT_TRUE(imported->skins.empty());
  EXPECT_FALSE(imported->instances[0].morphed);
  auto mesh = importGltfMesh(file.string());  // the baked positions (checked against the .bin above)
  ASSERT_TRUE(mesh.ok());
  EXPECT_EQ(imported->meshes[0].source.positions, mesh->positions);
  auto scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  EXPECT_TRUE(scene->skinnedObjects.empty());
  EXPECT_EQ(scene->meshes[0].morphTargetCount, 0u);
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
