// Tests for the material, texture and tangent import of importGltfScene on a generated glTF that sets every
// material field (texture transforms, second uv set, tangents under mirroring, invalid tangents, missing images), the
// baked textures' pack round trip, and the vertex streams that keep tangents and second uvs apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_assets.h"
#include "texture_test.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/asset/texture_bake.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using test::base64;
using test::randomRgba;
using test::TextureTest;

// --- a generated glTF that sets every material field -----------------------------------------------------

class MaterialFixture : public TextureTest {
 protected:
  // One triangle (0,0,0) (1,0,0) (0,1,0), normal +Z, uv0 = xy, uv1 = xy / 2, tangent (1,0,0,1); used by a
  // plain node and by a mirrored one (scale -1 in x). Material 0 sets every field, material 1 none.
  fs::path write() {
    writePng("colour map.png", 8, 8, randomRgba(8, 8, 1));
    writePng("data.png", 4, 4, randomRgba(4, 4, 2));
    std::vector<uint8_t> embedded = test::fileBytes(writePng("embedded.png", 4, 2, randomRgba(4, 2, 3)));
    fs::remove(dir_ / "embedded.png");
    const float vertexData[] = {0, 0, 0, 1, 0, 0, 0, 1, 0,            // POSITION
                                0, 0, 1, 0, 0, 1, 0, 0, 1,            // NORMAL
                                0, 0, 1, 0, 0, 1,                     // TEXCOORD_0
                                0, 0, 0.5f, 0, 0, 0.5f,               // TEXCOORD_1
                                1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1};  // TANGENT
    std::vector<uint8_t> buffer(sizeof(vertexData));
    std::memcpy(buffer.data(), vertexData, sizeof(vertexData));
    auto view = [](int offset, int length) { return json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}}; };
    auto accessor = [](int bufferView, const char* type) {
      return json{{"bufferView", bufferView}, {"componentType", 5126}, {"count", 3}, {"type", type}};
    };
    json positions = accessor(0, "VEC3");
    positions["min"] = {0, 0, 0};
    positions["max"] = {1, 1, 0};
    json full = {
        {"name", "full"},
        {"pbrMetallicRoughness",
         {{"baseColorFactor", {0.5, 0.25, 1.0, 0.75}},
          {"metallicFactor", 0.3},
          {"roughnessFactor", 0.6},
          {"baseColorTexture",
           {{"index", 0},
            {"extensions",
             {{"KHR_texture_transform", {{"offset", {0.5, -0.25}}, {"rotation", 0.3}, {"scale", {2, 3}}, {"texCoord", 1}}}}}}},
          {"metallicRoughnessTexture", {{"index", 1}}}}},
        {"normalTexture", {{"index", 1}, {"scale", 0.8}, {"texCoord", 1}}},
        {"occlusionTexture", {{"index", 2}, {"strength", 0.4}}},
        {"emissiveTexture", {{"index", 3}}},
        {"emissiveFactor", {1.0, 0.5, 0.25}},
        {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4.0}}}}},
        {"alphaMode", "MASK"},
        {"alphaCutoff", 0.3},
        {"doubleSided", true}};
    json doc = {
        {"asset", {{"version", "2.0"}}},
        {"extensionsUsed", {"KHR_texture_transform", "KHR_materials_emissive_strength"}},
        {"buffers", {{{"byteLength", buffer.size()}, {"uri", "data:application/octet-stream;base64," + base64(buffer)}}}},
        {"bufferViews", {view(0, 36), view(36, 36), view(72, 24), view(96, 24), view(120, 48)}},
        {"accessors", {positions, accessor(1, "VEC3"), accessor(2, "VEC2"), accessor(3, "VEC2"), accessor(4, "VEC4")}},
        {"images", {{{"uri", "colour%20map.png"}}, {{"uri", "data.png"}}, {{"uri", "data:image/png;base64," + base64(embedded)}}}},
        {"samplers",
         {{{"magFilter", 9728}, {"minFilter", 9984}, {"wrapS", 33071}, {"wrapT", 33648}},
          {{"minFilter", 9729}, {"wrapS", 10497}},
          json::object()}},
        {"textures", {{{"source", 0}, {"sampler", 0}}, {{"source", 1}, {"sampler", 1}}, {{"source", 2}}, {{"source", 0}, {"sampler", 2}}}},
        {"materials", {full, {{"name", "plain"}}}},
        {"meshes",
         {{{"name", "tri"},
           {"primitives",
            {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}, {"TEXCOORD_1", 3}, {"TANGENT", 4}}},
              {"material", 0}}}}}}},
        {"nodes", {{{"mesh", 0}}, {{"mesh", 0}, {"scale", {-1, 1, 1}}, {"translation", {3, 0, 0}}}}},
        {"scenes", {{{"nodes", {0, 1}}}}},
        {"scene", 0}};
    const fs::path path = dir_ / "materials.gltf";
    std::ofstream(path) << doc.dump();
    return path;
  }
};

TEST_F(MaterialFixture, EveryMaterialFieldIsImported) {
  const fs::path path = write();
  REQUIRE_OIIO();
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_EQ(s->materials.size(), 2u);
  const Material& m = s->materials[0];
  EXPECT_EQ(m.name, "full");
  EXPECT_EQ(m.baseColor, glm::vec4(0.5f, 0.25f, 1.0f, 0.75f));
  EXPECT_FLOAT_EQ(m.metallic, 0.3f);
  EXPECT_FLOAT_EQ(m.roughness, 0.6f);
  EXPECT_FLOAT_EQ(m.normalScale, 0.8f);
  EXPECT_FLOAT_EQ(m.occlusionStrength, 0.4f);
  EXPECT_EQ(m.emissive, glm::vec3(1.0f, 0.5f, 0.25f));
  EXPECT_FLOAT_EQ(m.emissiveStrength, 4.0f);
  EXPECT_EQ(m.alphaMode, AlphaMode::Mask);
  EXPECT_FLOAT_EQ(m.alphaCutoff, 0.3f);
  EXPECT_TRUE(m.doubleSided);
  // Texture references: glTF texture, image, URI, set, sampler.
  EXPECT_EQ(m.baseColorTexture.texture, 0);
  EXPECT_EQ(m.baseColorTexture.image, 0);
  EXPECT_EQ(m.baseColorTexture.uri, "colour%20map.png");
  EXPECT_EQ(m.baseColorTexture.texCoord, 1u);  // KHR_texture_transform's texCoord overrides 0
  const SamplerState nearestClampMirror{WrapMode::ClampToEdge, WrapMode::MirroredRepeat, TextureFilter::Nearest,
                                        TextureFilter::Nearest, MipFilter::Nearest};
  EXPECT_EQ(m.baseColorTexture.sampler, nearestClampMirror);
  EXPECT_EQ(m.metallicRoughnessTexture.image, 1);
  const SamplerState linearNoMips{WrapMode::Repeat, WrapMode::Repeat, TextureFilter::Linear, TextureFilter::Linear,
                                  MipFilter::None};
  EXPECT_EQ(m.metallicRoughnessTexture.sampler, linearNoMips);
  EXPECT_EQ(m.normalTexture.image, 1);
  EXPECT_EQ(m.normalTexture.texCoord, 1u);
  EXPECT_EQ(m.occlusionTexture.image, 2);
  EXPECT_EQ(m.occlusionTexture.uri, "");  // embedded (data: URI)
  EXPECT_EQ(m.occlusionTexture.sampler, SamplerState{});  // no sampler: repeat, trilinear
  EXPECT_EQ(m.emissiveTexture.texture, 3);
  EXPECT_EQ(m.emissiveTexture.sampler, SamplerState{});  // sampler with nothing set
  for (const TextureRef* t : textureSlots(m)) EXPECT_EQ(t->baked, -1);  // not baked by import
  // Defaults of glTF.
  const Material& plain = s->materials[1];
  EXPECT_EQ(plain.baseColor, glm::vec4(1.0f));
  EXPECT_EQ(plain.metallic, 1.0f);
  EXPECT_EQ(plain.roughness, 1.0f);
  EXPECT_EQ(plain.emissive, glm::vec3(0.0f));
  EXPECT_EQ(plain.emissiveStrength, 1.0f);
  EXPECT_EQ(plain.normalScale, 1.0f);
  EXPECT_EQ(plain.occlusionStrength, 1.0f);
  for (const TextureRef* t : textureSlots(plain)) EXPECT_EQ(*t, TextureRef{});
  // Images: external ones resolved (percent-decoded), the data: URI kept as bytes.
  ASSERT_EQ(s->images.size(), 3u);
  EXPECT_EQ(fs::path(s->images[0].path), dir_ / "colour map.png");
  EXPECT_TRUE(s->images[0].bytes.empty());
  EXPECT_TRUE(s->images[2].path.empty());
  EXPECT_GT(s->images[2].bytes.size(), 8u);
}

TEST_F(MaterialFixture, TextureTransformMatrixMatchesTheExtensionsFormula) {
  const fs::path path = write();
  REQUIRE_OIIO();
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  const glm::mat3x2& m = s->materials[0].baseColorTexture.transform;
  // By hand: T(0.5, -0.25) * R(0.3) * S(2, 3), R = [cos sin; -sin cos].
  const double c = std::cos(0.3), sn = std::sin(0.3);
  const double expected[3][2] = {{2 * c, -2 * sn}, {3 * sn, 3 * c}, {0.5, -0.25}};
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 2; ++row) EXPECT_NEAR(m[col][row], expected[col][row], 1e-6) << col << "," << row;
  // And applied to a point, step by step as the extension describes: scale, rotate, translate.
  const glm::dvec2 uv(0.25, 0.5);
  const glm::dvec2 scaled = uv * glm::dvec2(2, 3);
  const glm::dvec2 rotated(c * scaled.x + sn * scaled.y, -sn * scaled.x + c * scaled.y);
  const glm::dvec2 moved = rotated + glm::dvec2(0.5, -0.25);
  const glm::vec2 ours = m * glm::vec3(uv, 1.0);
  EXPECT_NEAR(ours.x, moved.x, 1e-6);
  EXPECT_NEAR(ours.y, moved.y, 1e-6);
  EXPECT_EQ(s->materials[0].metallicRoughnessTexture.transform, glm::mat3x2(1.0f));  // no extension: identity
}

// World bitangent as a shader computes it (cross(n, t) * w in world space) against the surface's dP/dv.
void expectTangentFrameFollowsUvs(const MeshSource& m, const glm::dmat4& transform, const std::string& what) {
  ASSERT_EQ(m.tangents.size(), m.positions.size()) << what;
  const glm::dmat3 linear(transform);
  const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(linear));
  glm::dvec3 p[3];
  glm::dvec2 uv[3];
  for (int k = 0; k < 3; ++k) {
    p[k] = linear * glm::dvec3(m.positions[m.indices[size_t(k)]]);
    uv[k] = glm::dvec2(m.uvs[m.indices[size_t(k)]]);
  }
  // [p1-p0 p2-p0] = [dPdu dPdv] * [[du1 du2] [dv1 dv2]]
  const glm::dmat2 duv(uv[1] - uv[0], uv[2] - uv[0]);
  const glm::dmat2 inv = glm::inverse(duv);
  const glm::dvec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
  const glm::dvec3 dPdu = e1 * inv[0][0] + e2 * inv[0][1];
  const glm::dvec3 dPdv = e1 * inv[1][0] + e2 * inv[1][1];
  for (uint32_t i : m.indices) {
    const glm::vec4 t = m.tangents[i];
    const glm::dvec3 n = glm::normalize(normalMatrix * glm::dvec3(m.normals[i]));
    const glm::dvec3 tw = glm::normalize(linear * glm::dvec3(t));
    const glm::dvec3 b = glm::cross(n, tw) * double(t.w);
    EXPECT_GT(glm::dot(tw, glm::normalize(dPdu)), 0.99) << what;
    EXPECT_GT(glm::dot(b, glm::normalize(dPdv)), 0.99) << what;
  }
}

TEST_F(MaterialFixture, TangentsAndSecondUvSetSurviveMirroring) {
  const fs::path path = write();
  REQUIRE_OIIO();
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_EQ(s->meshes.size(), 2u);  // plain + mirrored variant
  for (const ImportedInstance& inst : s->instances) {
    const ImportedMesh& mesh = s->meshes[inst.mesh];
    ASSERT_EQ(mesh.source.uvs1.size(), 3u);
    EXPECT_EQ(mesh.source.uvs1[1], glm::vec2(0.5f, 0.0f));
    EXPECT_EQ(mesh.source.tangents[0].w, mesh.mirrored ? -1.0f : 1.0f);
    expectTangentFrameFollowsUvs(mesh.source, inst.transform, mesh.mirrored ? "mirrored instance" : "plain instance");
  }
  // Flattened import: the transform is baked into the vertices, so the frame must hold with identity.
  Result<MeshSource> flat = importGltfMesh(path.string());
  ASSERT_TRUE(flat) << flat.error().message;
  ASSERT_EQ(flat->indices.size(), 6u);
  for (size_t tri = 0; tri < 2; ++tri) {
    MeshSource one = *flat;
    one.indices.assign(flat->indices.begin() + std::ptrdiff_t(3 * tri), flat->indices.begin() + std::ptrdiff_t(3 * tri + 3));
    expectTangentFrameFollowsUvs(one, glm::dmat4(1.0), "flattened triangle " + std::to_string(tri));
  }
  // The streams go through buildMesh and a pack.
  Result<Scene> scene = buildImportedScene(*s);
  ASSERT_TRUE(scene) << scene.error().message;
  EXPECT_EQ(scene->meshes[0].tangents.size(), scene->meshes[0].vertices.size());
  EXPECT_EQ(scene->meshes[0].uvs1.size(), scene->meshes[0].vertices.size());
}

TEST_F(MaterialFixture, InvalidTangentsAreDroppedWithAWarning) {
  const fs::path path = write();
  REQUIRE_OIIO();
  json doc = json::parse(std::ifstream(path));
  doc["accessors"][4]["bufferView"] = 1;  // TANGENT reads the normals: (0,0,1,0), ... w = 0 is invalid
  doc["bufferViews"][1]["byteLength"] = 48;
  std::ofstream(path) << doc.dump();
  GltfImportReport report;
  Result<ImportedScene> s = importGltfScene(path.string(), {}, &report);
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_TRUE(s->meshes[0].source.tangents.empty());
  bool warned = false;
  for (const std::string& w : report.warnings) warned |= w.find("TANGENT") != std::string::npos && w.find("dropped") != std::string::npos;
  EXPECT_TRUE(warned);
}

TEST_F(MaterialFixture, BakedTexturesAndPackRoundTrip) {
  const fs::path path = write();
  REQUIRE_OIIO();
  Result<ImportedScene> imported = importGltfScene(path.string());
  ASSERT_TRUE(imported) << imported.error().message;
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene) << scene.error().message;
  TextureBakeReport report;
  TextureBakeOptions rgba8;  // this test pins the uncompressed layout (test_texture_compression.cpp: BC)
  rgba8.encoding = TextureEncoding::Rgba8;
  Status baked = bakeTextures(*imported, rgba8, &scene.value(), &report);
  ASSERT_TRUE(baked) << baked.error().message;
  // (image 0, sRGB) for base colour and emissive, (image 1, linear) for metallic-roughness and normal,
  // (image 2, linear) for occlusion: 3 textures; classes 8 sRGB (1 layer) and 4 linear (2 layers).
  ASSERT_EQ(scene->textures.size(), 3u);
  const Material& m = scene->materials[0];
  EXPECT_EQ(m.baseColorTexture.baked, 0);
  EXPECT_EQ(m.emissiveTexture.baked, 0);
  EXPECT_EQ(m.metallicRoughnessTexture.baked, 1);
  EXPECT_EQ(m.normalTexture.baked, 1);
  EXPECT_EQ(m.occlusionTexture.baked, 2);
  EXPECT_EQ(scene->textures[0].colorSpace, ColorSpace::Srgb);
  EXPECT_EQ(scene->textures[2].colorSpace, ColorSpace::Linear);
  EXPECT_EQ(scene->textures[2].originalWidth, 4u);
  EXPECT_EQ(scene->textures[2].originalHeight, 2u);
  ASSERT_EQ(scene->textureClasses.size(), 2u);
  EXPECT_EQ(scene->textureClasses[0].size, 8u);
  EXPECT_EQ(scene->textureClasses[0].layers, 1u);
  EXPECT_EQ(scene->textureClasses[1].size, 4u);
  EXPECT_EQ(scene->textureClasses[1].layers, 2u);
  EXPECT_EQ(scene->textureClasses[1].mipCount, 3u);
  EXPECT_EQ(scene->textures[2].sizeClass, 1u);
  EXPECT_EQ(scene->textures[2].layer, 1u);
  EXPECT_EQ(report.notes.size(), 1u);  // the 4x2 image
  EXPECT_EQ(report.texelBytes, (64 + 16 + 4 + 1) * 4u + 2 * (16 + 4 + 1) * 4u);
  // Layer 0 of the sRGB class, mip 0, is the PNG's texels (square power of two: no resampling).
  const std::vector<uint8_t> source = randomRgba(8, 8, 1);
  const TextureClass& srgb = scene->textureClasses[0];
  EXPECT_TRUE(std::equal(source.begin(), source.end(), srgb.texels.begin() + std::ptrdiff_t(srgb.offset(0, 0))));

  Result<std::vector<uint8_t>> bytes = serializePack(*scene);
  ASSERT_TRUE(bytes) << bytes.error().message;
  Result<Scene> back = parsePack(bytes->data(), bytes->size(), "fixture.vbp");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->textures, scene->textures);
  EXPECT_EQ(back->textureClasses, scene->textureClasses);
  for (size_t i = 0; i < scene->materials.size(); ++i) {
    const auto a = textureSlots(scene->materials[i]);
    const auto b = textureSlots(back->materials[i]);
    for (size_t t = 0; t < a.size(); ++t) EXPECT_EQ(*a[t], *b[t]) << "material " << i << " slot " << t;
    EXPECT_EQ(back->materials[i].emissiveStrength, scene->materials[i].emissiveStrength);
  }
  EXPECT_EQ(back->meshes[0].tangents, scene->meshes[0].tangents);
  EXPECT_EQ(back->meshes[0].uvs1, scene->meshes[0].uvs1);
}

// A missing image: with dropUndecodableImages off (--strict-images) a clear FileNotFound naming it; by default its
// texture is dropped from every slot that used it, with one warning naming the image, and the others bake.
TEST_F(MaterialFixture, MissingExternalImageIsAClearError) {
  const fs::path path = write();
  REQUIRE_OIIO();
  fs::remove(dir_ / "data.png");
  Result<ImportedScene> imported = importGltfScene(path.string());
  ASSERT_TRUE(imported) << imported.error().message;  // import does not read pixels
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene);
  {
    Scene dropped = *scene;
    TextureBakeReport report;
    ASSERT_TRUE(bakeTextures(*imported, {}, &dropped, &report));
    ASSERT_EQ(report.warnings.size(), 1u);
    EXPECT_NE(report.warnings[0].find("image 'data.png'"), std::string::npos) << report.warnings[0];
    EXPECT_NE(report.warnings[0].find("its texture is dropped"), std::string::npos) << report.warnings[0];
    size_t slotsLeft = 0, slotsBefore = 0;
    for (size_t m = 0; m < dropped.materials.size(); ++m) {
      for (size_t slot = 0; slot < kTextureSlotCount; ++slot) {
        const TextureRef& before = *textureSlots(scene->materials[m])[slot];
        const TextureRef& after = *textureSlots(dropped.materials[m])[slot];
        slotsBefore += before.image >= 0;
        slotsLeft += after.image >= 0;
        if (after.image >= 0) {
          EXPECT_EQ(after.image, before.image);
          ASSERT_GE(after.baked, 0);
          ASSERT_LT(size_t(after.baked), dropped.textures.size());
          EXPECT_EQ(dropped.textures[size_t(after.baked)].sourceImage, after.image);
        } else if (before.image >= 0) {
          EXPECT_EQ(imported->images[size_t(before.image)].uri, "data.png");
        }
      }
    }
    EXPECT_LT(slotsLeft, slotsBefore);
  }
  TextureBakeOptions strict;
  strict.dropUndecodableImages = false;
  Status s = bakeTextures(*imported, strict, &scene.value());
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::FileNotFound);
  EXPECT_NE(s.error().message.find("image 'data.png'"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("not found"), std::string::npos) << s.error().message;
  // A bad size option is refused before any work.
  Status bad = bakeTextures(*imported, {300}, &scene.value());
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().code, ErrorCode::InvalidArgument);
}

TEST(MeshBuildStreams, DifferentTangentsOrSecondUvsAreDifferentVertices) {
  // Two triangles over the same 4 corners, written as 6 vertices; 1/4 and 2/5 are duplicates except for the
  // optional streams.
  MeshSource m;
  m.name = "quad";
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 0}};
  m.normals.assign(6, glm::vec3(0, 0, 1));
  m.indices = {0, 1, 2, 5, 4, 3};
  Result<Mesh> plain = buildMesh(m);
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->vertices.size(), 4u);
  m.tangents.assign(6, glm::vec4(1, 0, 0, 1));
  Result<Mesh> same = buildMesh(m);
  ASSERT_TRUE(same);
  EXPECT_EQ(same->vertices.size(), 4u);
  m.tangents[4].w = m.tangents[5].w = -1.0f;
  Result<Mesh> handed = buildMesh(m);
  ASSERT_TRUE(handed);
  EXPECT_EQ(handed->vertices.size(), 6u);
  EXPECT_EQ(handed->tangents.size(), 6u);
  m.tangents.clear();
  m.uvs1 = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {1, 0}, {0, 0.5f}};
  Result<Mesh> uv1 = buildMesh(m);
  ASSERT_TRUE(uv1);
  EXPECT_EQ(uv1->vertices.size(), 5u);
  // Each output vertex keeps its own streams (the remap moves them together).
  for (size_t v = 0; v < uv1->vertices.size(); ++v) {
    const gpu::Vertex& x = uv1->vertices[v];
    if (x.px == 0.0f && x.py == 1.0f) {
      EXPECT_TRUE(uv1->uvs1[v] == glm::vec2(0, 1) || uv1->uvs1[v] == glm::vec2(0, 0.5f));
    }
    if (x.px == 1.0f && x.py == 1.0f) {
      EXPECT_EQ(uv1->uvs1[v], glm::vec2(1, 1));
    }
  }
  m.tangents.assign(6, glm::vec4(0, 0, 0, 1));  // w without a direction
  EXPECT_FALSE(buildMesh(m));
}

}  // namespace
}  // namespace visbuf
