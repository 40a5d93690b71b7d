// Tests for importGltfScene (engine/asset/gltf_import.h): node hierarchy kept as instances, per-material
// meshes, mirrored variants, materials. Expected counts come from reading the sample files' JSON (see each
// test).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "test_assets.h"
#include "temp_dir_test.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using test::assetPath;

// Positions of the flattened import equal, in order, every instance's mesh positions transformed by the
// instance transform (both walk the same nodes in the same order; each test asset has one material per mesh).
void expectMatchesFlattened(const fs::path& path, const ImportedScene& scene) {
  Result<MeshSource> flat = importGltfMesh(path.string());
  ASSERT_TRUE(flat) << flat.error().message;
  size_t at = 0;
  size_t triangles = 0;
  for (const ImportedInstance& inst : scene.instances) {
    const MeshSource& m = scene.meshes[inst.mesh].source;
    triangles += m.indices.size() / 3;
    for (const glm::vec3& p : m.positions) {
      ASSERT_LT(at, flat->positions.size());
      const glm::dvec3 world = glm::dvec3(inst.transform * glm::dvec4(glm::dvec3(p), 1.0));
      const glm::dvec3 expected(flat->positions[at]);
      EXPECT_NEAR(glm::length(world - expected), 0.0, 1e-4 * (1.0 + glm::length(expected)))
          << "vertex " << at;
      ++at;
    }
  }
  EXPECT_EQ(at, flat->positions.size());
  EXPECT_EQ(triangles, flat->indices.size() / 3);
}

TEST(GltfScene, OrientationTest) {
  // 13 nodes, each with its own one-primitive mesh (13 meshes), 7 materials, no textures.
  const fs::path path = assetPath("OrientationTest/glTF/OrientationTest.gltf");
  REQUIRE_ASSET(path);
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->meshes.size(), 13u);
  EXPECT_EQ(s->instances.size(), 13u);
  ASSERT_EQ(s->materials.size(), 7u);
  EXPECT_EQ(s->materials[0].name, "BaseMaterial");
  EXPECT_NEAR(s->materials[1].baseColor.r, 0.8f, 1e-6f);  // MatX1: (0.8, 0, 0, 1)
  EXPECT_EQ(s->materials[1].baseColor.g, 0.0f);
  for (const ImportedInstance& inst : s->instances) {
    EXPECT_EQ(inst.material, s->meshes[inst.mesh].material);
    EXPECT_FALSE(s->meshes[inst.mesh].mirrored);
  }
  expectMatchesFlattened(path, *s);
}

TEST(GltfScene, MultiUVTest) {
  // 3 nodes, one of them with the single mesh; 1 material whose base colour texture is texture 0 = uv0.png.
  const fs::path path = assetPath("MultiUVTest/glTF/MultiUVTest.gltf");
  REQUIRE_ASSET(path);
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->meshes.size(), 1u);
  EXPECT_EQ(s->instances.size(), 1u);
  ASSERT_EQ(s->materials.size(), 1u);
  EXPECT_EQ(s->materials[0].baseColorTexture.texture, 0);
  EXPECT_EQ(s->materials[0].baseColorTexture.image, 0);
  EXPECT_EQ(s->materials[0].baseColorTexture.uri, "uv0.png");
  EXPECT_EQ(s->materials[0].baseColor, glm::vec4(1.0f));
  expectMatchesFlattened(path, *s);
}

TEST(GltfScene, Fox) {
  // 26 nodes (a skeleton) and one skinned mesh used by one node: imported in rest pose as one instance.
  const fs::path path = assetPath("Fox/glTF/Fox.gltf");
  REQUIRE_ASSET(path);
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->meshes.size(), 1u);
  ASSERT_EQ(s->instances.size(), 1u);
  ASSERT_EQ(s->materials.size(), 1u);
  EXPECT_EQ(s->materials[0].name, "fox_material");
  EXPECT_EQ(s->materials[0].baseColorTexture.uri, "Texture.png");
  EXPECT_EQ(s->meshes[0].source.indices.size() / 3, 576u);
  expectMatchesFlattened(path, *s);
}

TEST(GltfScene, AlphaBlendModeTest) {
  // 9 nodes with 9 one-primitive meshes; 6 materials: MatBed (opaque), MatBlend (BLEND), MatCutoff25 /
  // MatCutoff75 / MatCutoffDefault (MASK 0.25 / 0.75 / default 0.5), MatOpaque; all but MatBed double-sided.
  const fs::path path = assetPath("AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf");
  REQUIRE_ASSET(path);
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->meshes.size(), 9u);
  EXPECT_EQ(s->instances.size(), 9u);
  ASSERT_EQ(s->materials.size(), 6u);
  const auto& m = s->materials;
  EXPECT_EQ(m[0].alphaMode, AlphaMode::Opaque);
  EXPECT_FALSE(m[0].doubleSided);
  EXPECT_EQ(m[0].baseColorTexture.uri, "MatBed_baseColor.jpg");
  EXPECT_EQ(m[1].alphaMode, AlphaMode::Blend);
  EXPECT_EQ(m[2].alphaMode, AlphaMode::Mask);
  EXPECT_FLOAT_EQ(m[2].alphaCutoff, 0.25f);
  EXPECT_FLOAT_EQ(m[3].alphaCutoff, 0.75f);
  EXPECT_EQ(m[4].alphaMode, AlphaMode::Mask);
  EXPECT_FLOAT_EQ(m[4].alphaCutoff, 0.5f);
  EXPECT_EQ(m[5].alphaMode, AlphaMode::Opaque);
  for (size_t i = 1; i < 6; ++i) {
    EXPECT_TRUE(m[i].doubleSided) << i;
    EXPECT_EQ(m[i].baseColorTexture.uri, "AlphaBlendLabels.png") << i;
  }
  expectMatchesFlattened(path, *s);
}

// A synthetic file: one mesh with three primitives (material 0, material 1, no material) used by a plain node
// and by a mirrored node (scale -1 in x), plus a second plain node using the same mesh.
class GltfSceneSynthetic : public test::TempDirTest {
 protected:
  fs::path write() {
    // Triangle (0,0,0) (1,0,0) (0,1,0): counter-clockwise seen from +Z, normals +Z.
    const float data[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    std::string bytes(reinterpret_cast<const char*>(data), sizeof(data));
    static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string b64;
    for (size_t i = 0; i < bytes.size(); i += 3) {  // 72 bytes: a multiple of 3, no padding needed
      const uint32_t t = (uint32_t(uint8_t(bytes[i])) << 16) | (uint32_t(uint8_t(bytes[i + 1])) << 8) |
                         uint32_t(uint8_t(bytes[i + 2]));
      for (int k = 3; k >= 0; --k) b64 += kAlphabet[(t >> (6 * k)) & 63];
    }
    json prim = {{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}};
    json p0 = prim, p1 = prim, p2 = prim;
    p0["material"] = 0;
    p1["material"] = 1;
    json doc = {{"asset", {{"version", "2.0"}}},
                {"buffers", {{{"byteLength", 72}, {"uri", "data:application/octet-stream;base64," + b64}}}},
                {"bufferViews",
                 {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
                  {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 36}}}},
                {"accessors",
                 {{{"bufferView", 0},
                   {"componentType", 5126},
                   {"count", 3},
                   {"type", "VEC3"},
                   {"min", {0, 0, 0}},
                   {"max", {1, 1, 0}}},
                  {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}}}},
                {"materials",
                 {{{"name", "red"},
                   {"pbrMetallicRoughness", {{"baseColorFactor", {1.0, 0.0, 0.0, 0.5}}}},
                   {"alphaMode", "BLEND"}},
                  {{"name", "green"},
                   {"pbrMetallicRoughness", {{"baseColorFactor", {0.0, 1.0, 0.0, 1.0}}}},
                   {"doubleSided", true}}}},
                {"meshes", {{{"name", "tri"}, {"primitives", {p0, p1, p2}}}}},
                {"nodes",
                 {{{"children", {1, 2, 3}}, {"translation", {0, 0, -5}}},
                  {{"mesh", 0}},
                  {{"mesh", 0}, {"scale", {-1, 1, 1}}, {"translation", {3, 0, 0}}},
                  {{"mesh", 0}, {"translation", {-3, 0, 0}}}}},
                {"scenes", {{{"nodes", {0}}}}},
                {"scene", 0}};
    const fs::path path = dir_ / "synthetic.gltf";
    std::ofstream(path) << doc.dump();
    return path;
  }
};

TEST_F(GltfSceneSynthetic, MaterialGroupsMirroredVariantsAndDefaultMaterial) {
  const fs::path path = write();
  GltfImportReport report;
  Result<ImportedScene> s = importGltfScene(path.string(), {}, &report);
  ASSERT_TRUE(s) << s.error().message;
  // 3 material groups x (plain, mirrored) = 6 meshes; 3 nodes x 3 groups = 9 instances.
  EXPECT_EQ(s->meshes.size(), 6u);
  EXPECT_EQ(s->instances.size(), 9u);
  EXPECT_EQ(report.primitivesImported, 9u);
  ASSERT_EQ(s->materials.size(), 3u);  // red, green, appended default
  EXPECT_EQ(s->materials[2].name, "default");
  EXPECT_EQ(s->materials[0].alphaMode, AlphaMode::Blend);
  EXPECT_EQ(s->materials[0].baseColor, glm::vec4(1.0f, 0.0f, 0.0f, 0.5f));
  EXPECT_TRUE(s->materials[1].doubleSided);
  size_t mirroredInstances = 0;
  for (const ImportedInstance& inst : s->instances) {
    const ImportedMesh& mesh = s->meshes[inst.mesh];
    EXPECT_EQ(inst.material, mesh.material);
    const bool negative = glm::determinant(glm::dmat3(inst.transform)) < 0.0;
    EXPECT_EQ(mesh.mirrored, negative);
    mirroredInstances += negative;
    // The world-space winding normal agrees with the transformed vertex normal: front faces stay
    // counter-clockwise for every instance, mirrored or not.
    const MeshSource& m = mesh.source;
    ASSERT_EQ(m.indices.size(), 3u);
    glm::dvec3 p[3];
    for (int k = 0; k < 3; ++k)
      p[k] = glm::dvec3(inst.transform * glm::dvec4(glm::dvec3(m.positions[m.indices[k]]), 1.0));
    const glm::dvec3 face = glm::cross(p[1] - p[0], p[2] - p[0]);
    const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(glm::dmat3(inst.transform)));
    const glm::dvec3 n = normalMatrix * glm::dvec3(m.normals[m.indices[0]]);
    EXPECT_GT(glm::dot(face, n), 0.0) << "instance of node " << inst.node;
  }
  EXPECT_EQ(mirroredInstances, 3u);
  // Node 2's world transform: parent translation (0,0,-5) * own T(3,0,0) * S(-1,1,1).
  bool found = false;
  for (const ImportedInstance& inst : s->instances) {
    if (inst.node != 2) continue;
    found = true;
    EXPECT_EQ(inst.transform[0][0], -1.0);
    EXPECT_EQ(inst.transform[3][0], 3.0);
    EXPECT_EQ(inst.transform[3][2], -5.0);
  }
  EXPECT_TRUE(found);
}

TEST_F(GltfSceneSynthetic, MissingMaterialIsAnError) {
  const fs::path path = write();
  json doc = json::parse(std::ifstream(path));
  doc["meshes"][0]["primitives"][0]["material"] = 7;
  std::ofstream(path) << doc.dump();
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(s.error().message.find("meshes[0].primitives[0].material: 7 is not a valid index; materials has 2 entries"),
            std::string::npos)
      << s.error().message;
}

}  // namespace
}  // namespace visbuf
