// Tests for texture baking (engine/asset/texture_bake.h): mip chains against a double-precision box filter
// (sRGB-correct), size rules and corrupt images; and the texture import of the sample assets (samplers, uv sets,
// embedded images). The material fixture that sets every material field: test_material_import.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
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
#include "visbuf/core/image_io.h"

// LeakSanitizer (sanitizer build): OpenImageIO 2.4 loses an error string allocated in ImageInput::geterror when
// libpng aborts a corrupt PNG (about 31 bytes per corrupt file, CorruptImagesAreRejectedWithTheirName only; not
// reachable from our code, which closes and drains the reader). Unused in other builds.
extern "C" const char* __lsan_default_suppressions() { return "leak:OpenImageIO_v2_4::ImageInput::geterror\n"; }

namespace visbuf {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using test::assetPath;
using test::randomRgba;
using test::TextureTest;

// --- independent double-precision reference -------------------------------------------------------------

double srgbDecode(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

// The 8-bit sRGB code of a linear value: the encoding curve in double precision, rounded to nearest.
int srgbEncodeNearest(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  const double encoded = linear <= 0.0031308 ? linear * 12.92 : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
  return int(std::lround(encoded * 255.0));
}

// Mip level `level` of a square RGBA8 image by averaging 2^level x 2^level blocks of the linear-light values.
std::vector<int> referenceMip(const std::vector<uint8_t>& rgba, uint32_t size, uint32_t level, bool srgb) {
  const uint32_t block = 1u << level, out = size >> level;
  std::vector<int> result(size_t(out) * out * 4);
  for (uint32_t y = 0; y < out; ++y) {
    for (uint32_t x = 0; x < out; ++x) {
      for (int c = 0; c < 4; ++c) {
        double sum = 0.0;
        for (uint32_t j = 0; j < block; ++j) {
          for (uint32_t i = 0; i < block; ++i) {
            const double v = rgba[(size_t(y * block + j) * size + x * block + i) * 4 + size_t(c)] / 255.0;
            sum += srgb && c < 3 ? srgbDecode(v) : v;
          }
        }
        const double mean = sum / (block * block);
        result[(size_t(y) * out + x) * 4 + size_t(c)] =
            srgb && c < 3 ? srgbEncodeNearest(mean) : int(std::lround(mean * 255.0));
      }
    }
  }
  return result;
}


// --- steps ---------------------------------------------------------------------------------------------

TEST(TextureMath, SrgbEncodingIsExactlyRounded) {
  for (int i = 0; i <= 4000; ++i) {
    const double v = i / 4000.0;
    EXPECT_EQ(int(encodeSrgb8(float(v))), srgbEncodeNearest(v)) << v;
  }
  for (int k = 0; k < 256; ++k) EXPECT_EQ(int(encodeSrgb8(srgbToLinear(k / 255.0f))), k);  // round trip
  EXPECT_EQ(encodeSrgb8(-1.0f), 0);
  EXPECT_EQ(encodeSrgb8(2.0f), 255);
  EXPECT_EQ(encodeSrgb8(NAN), 0);
}

// The bake keeps an 8-bit square power-of-two image's codes as its mip 0 (bakeImage) instead of encoding their
// linear values again: that is exact only if every code comes back from its own linear value.
TEST(TextureMath, EightBitCodesSurviveTheLinearRoundTrip) {
  for (int k = 0; k < 256; ++k) {
    LinearImage one;
    one.width = one.height = 1;
    for (int c = 0; c < 4; ++c) one.rgba.push_back(codeToLinear(uint8_t(k), c < 3));
    const std::vector<uint8_t> srgb = encodeRgba8(one, ColorSpace::Srgb);
    EXPECT_EQ(srgb, std::vector<uint8_t>(4, uint8_t(k))) << "sRGB code " << k;
    for (float& v : one.rgba) v = codeToLinear(uint8_t(k), false);
    EXPECT_EQ(encodeRgba8(one, ColorSpace::Linear), std::vector<uint8_t>(4, uint8_t(k))) << "linear code " << k;
    EXPECT_EQ(codeToLinear(uint8_t(k), true), srgbToLinear(float(k) / 255.0f));
  }
}

TEST(TextureMath, BakedSizeRoundsToTheNearestPowerOfTwoAndCaps) {
  EXPECT_EQ(bakedTextureSize(1, 1, 2048), 1u);
  EXPECT_EQ(bakedTextureSize(211, 211, 2048), 256u);  // BoxTexturedNonPowerOfTwo
  EXPECT_EQ(bakedTextureSize(300, 300, 2048), 256u);  // 300 < 1.5 * 256: down
  EXPECT_EQ(bakedTextureSize(383, 10, 2048), 256u);
  EXPECT_EQ(bakedTextureSize(384, 10, 2048), 512u);   // tie: up
  EXPECT_EQ(bakedTextureSize(400, 300, 2048), 512u);  // the larger side decides
  EXPECT_EQ(bakedTextureSize(3, 1, 2048), 4u);
  EXPECT_EQ(bakedTextureSize(4096, 4096, 2048), 2048u);
  EXPECT_EQ(bakedTextureSize(5000, 10, 1), 1u);
}

TEST_F(TextureTest, MipChainMatchesDoublePrecisionBoxFilter) {
  const uint32_t size = 32;
  const std::vector<uint8_t> rgba = randomRgba(size, size, 7);
  const std::vector<uint8_t> png = pngBytes(size, size, rgba);
  REQUIRE_OIIO();
  for (ColorSpace cs : {ColorSpace::Srgb, ColorSpace::Linear}) {
    SCOPED_TRACE(cs == ColorSpace::Srgb ? "sRGB" : "linear");
    Result<BakedImage> baked = bakeImage(png.data(), png.size(), "random.png", cs, 2048);
    ASSERT_TRUE(baked) << baked.error().message;
    EXPECT_EQ(baked->size, size);
    EXPECT_TRUE(baked->resizeNote.empty());
    ASSERT_EQ(baked->mips.size(), 6u);  // 32, 16, 8, 4, 2, 1
    EXPECT_EQ(baked->mips[0], rgba);    // level 0 is the image itself, bit for bit
    size_t exact = 0, total = 0;
    for (uint32_t level = 0; level < 6; ++level) {
      const std::vector<int> expected = referenceMip(rgba, size, level, cs == ColorSpace::Srgb);
      ASSERT_EQ(baked->mips[level].size(), expected.size());
      for (size_t i = 0; i < expected.size(); ++i) {
        EXPECT_LE(std::abs(int(baked->mips[level][i]) - expected[i]), 1) << "level " << level << " byte " << i;
        exact += int(baked->mips[level][i]) == expected[i];
        ++total;
      }
    }
    EXPECT_GE(double(exact), 0.99 * double(total));  // off by one only where float and double round apart
  }
  // sRGB-correct filtering differs from naive averaging of the encoded values: a black/white checker's 1x1 mip
  // is linear 0.5 = sRGB 188, not 128.
  std::vector<uint8_t> checker(2 * 2 * 4, 255);
  checker[0] = checker[1] = checker[2] = checker[12] = checker[13] = checker[14] = 0;
  const std::vector<uint8_t> checkerPng = pngBytes(2, 2, checker);
  Result<BakedImage> c = bakeImage(checkerPng.data(), checkerPng.size(), "checker", ColorSpace::Srgb, 2048);
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->mips[1], (std::vector<uint8_t>{188, 188, 188, 255}));
}

TEST_F(TextureTest, SizeCapDropsTopLevelsOfASquarePowerOfTwo) {
  const std::vector<uint8_t> rgba = randomRgba(64, 64, 11);
  const std::vector<uint8_t> png = pngBytes(64, 64, rgba);
  REQUIRE_OIIO();
  Result<BakedImage> baked = bakeImage(png.data(), png.size(), "big.png", ColorSpace::Srgb, 16);
  ASSERT_TRUE(baked) << baked.error().message;
  EXPECT_EQ(baked->size, 16u);
  EXPECT_EQ(baked->originalWidth, 64u);
  ASSERT_EQ(baked->mips.size(), 5u);
  EXPECT_NE(baked->resizeNote.find("size cap"), std::string::npos) << baked->resizeNote;
  const std::vector<int> expected = referenceMip(rgba, 64, 2, true);  // 4x4 blocks
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_LE(std::abs(int(baked->mips[0][i]) - expected[i]), 1) << i;
}

TEST_F(TextureTest, NonPowerOfTwoAndNonSquareImagesBecomeSquarePowerOfTwo) {
  // A constant colour survives any normalised resampling filter.
  std::vector<uint8_t> rgba(300 * 200 * 4);
  for (size_t i = 0; i < rgba.size(); i += 4) rgba[i] = 200, rgba[i + 1] = 100, rgba[i + 2] = 50, rgba[i + 3] = 128;
  const std::vector<uint8_t> png = pngBytes(300, 200, rgba);
  REQUIRE_OIIO();
  Result<BakedImage> baked = bakeImage(png.data(), png.size(), "wide.png", ColorSpace::Srgb, 2048);
  ASSERT_TRUE(baked) << baked.error().message;
  EXPECT_EQ(baked->size, 256u);
  EXPECT_EQ(baked->originalWidth, 300u);
  EXPECT_EQ(baked->originalHeight, 200u);
  EXPECT_EQ(baked->mips.size(), 9u);
  EXPECT_NE(baked->resizeNote.find("300x200 -> 256x256"), std::string::npos) << baked->resizeNote;
  for (const std::vector<uint8_t>& level : baked->mips) {
    for (size_t i = 0; i < level.size(); i += 4) {
      ASSERT_NEAR(level[i], 200, 1) << i;
      ASSERT_NEAR(level[i + 1], 100, 1);
      ASSERT_NEAR(level[i + 2], 50, 1);
      ASSERT_NEAR(level[i + 3], 128, 1);
    }
  }
  // 211x211 (NPOT, square) rounds down to 256? No: 211 >= 1.5 * 128, so up to 256.
  const std::vector<uint8_t> npot = pngBytes(211, 211, randomRgba(211, 211, 3));
  Result<BakedImage> up = bakeImage(npot.data(), npot.size(), "npot.png", ColorSpace::Linear, 2048);
  ASSERT_TRUE(up) << up.error().message;
  EXPECT_EQ(up->size, 256u);
  EXPECT_NE(up->resizeNote.find("non-power-of-two"), std::string::npos) << up->resizeNote;
}

TEST_F(TextureTest, CorruptImagesAreRejectedWithTheirName) {
  const std::vector<uint8_t> png = pngBytes(16, 16, randomRgba(16, 16, 5));
  REQUIRE_OIIO();
  ASSERT_GT(png.size(), 200u);
  std::vector<std::vector<uint8_t>> broken;
  std::vector<uint8_t> flipped = png;
  for (size_t i = png.size() / 2; i < png.size() / 2 + 16; ++i) flipped[i] ^= 0x5A;  // inside IDAT
  broken.push_back(flipped);
  broken.emplace_back(png.begin(), png.begin() + std::ptrdiff_t(png.size() / 2));  // truncated
  broken.emplace_back(png.begin(), png.begin() + 8);                               // signature only
  std::vector<uint8_t> gif = {'G', 'I', 'F', '8', '9', 'a', 1, 0, 1, 0};
  broken.push_back(gif);
  broken.emplace_back();
  for (size_t k = 0; k < broken.size(); ++k) {
    Result<BakedImage> r = bakeImage(broken[k].data(), broken[k].size(), "scene: image 3 'bad.png'", ColorSpace::Srgb, 2048);
    ASSERT_FALSE(r) << "case " << k;
    EXPECT_EQ(r.error().code, ErrorCode::MalformedInput) << r.error().message;
    EXPECT_EQ(r.error().message.rfind("scene: image 3 'bad.png': ", 0), 0u) << r.error().message;
  }
}

#if !VISBUF_WITH_OIIO
// A build without OpenImageIO (registered only there): an image step refuses with Unsupported, naming the build
// option, instead of decoding.
TEST(TextureBuild, WithoutOpenImageIoImagesAreRefusedNamingTheOption) {
  const std::vector<uint8_t> bytes = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  Result<BakedImage> r = bakeImage(bytes.data(), bytes.size(), "a.png", ColorSpace::Srgb, 2048);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::Unsupported);
  EXPECT_NE(r.error().message.find("VISBUF_WITH_OIIO=OFF"), std::string::npos) << r.error().message;
}
#endif

// --- sample assets ------------------------------------------------------------------------------------

// DamagedHelmet is not redistributable: this test exists only when VISBUF_EXTRA_ASSETS has it.
EXTRA_ASSET_TEST(GltfTextures, DamagedHelmetHasFiveTexturesWithTheRightColourSpaces,
                 "DamagedHelmet/glTF-Binary/DamagedHelmet.glb") {
  Result<ImportedScene> imported = importGltfScene(asset.string());
  ASSERT_TRUE(imported) << imported.error().message;
  ASSERT_EQ(imported->materials.size(), 1u);
  const Material& m = imported->materials[0];
  EXPECT_EQ(m.emissive, glm::vec3(1.0f));
  // The five core slots are textured; the clearcoat slots (KHR_materials_clearcoat) are not.
  constexpr size_t kCoreSlots = 5;
  const auto importedSlots = textureSlots(m);
  for (size_t slot = 0; slot < importedSlots.size(); ++slot)
    EXPECT_EQ(importedSlots[slot]->image >= 0, slot < kCoreSlots) << slot;
  ASSERT_EQ(imported->images.size(), 5u);
  for (const ImportedImage& image : imported->images) EXPECT_FALSE(image.bytes.empty());  // GLB bufferViews
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene) << scene.error().message;
  TextureBakeOptions options;
  options.maxTextureSize = 128;  // keeps the test fast; the 2048 originals are downscaled
  SKIP_WITHOUT_OIIO();  // what follows bakes the images
  Status baked = bakeTextures(*imported, options, &scene.value());
  ASSERT_TRUE(baked) << baked.error().message;
  ASSERT_EQ(scene->textures.size(), 5u);
  const Material& bm = scene->materials[0];
  const auto slots = textureSlots(bm);
  for (size_t slot = 0; slot < kCoreSlots; ++slot) {
    const Texture& t = scene->textures[size_t(slots[slot]->baked)];
    EXPECT_EQ(t.colorSpace, slot == 0 || slot == 4 ? ColorSpace::Srgb : ColorSpace::Linear) << slot;
    EXPECT_EQ(t.originalWidth, 2048u);
    EXPECT_EQ(scene->textureClasses[t.sizeClass].size, 128u);
  }
  // Block-compressed by default: base colour and emissive share an sRGB BC1 class; metallic-roughness is linear
  // BC1, the normal map BC5, occlusion BC4.
  ASSERT_EQ(scene->textureClasses.size(), 4u);
  const auto classOf = [&](size_t slot) { return scene->textureClasses[scene->textures[size_t(slots[slot]->baked)].sizeClass]; };
  EXPECT_EQ(classOf(0).format, TextureFormat::Bc1);
  EXPECT_EQ(classOf(0).layers, 2u);
  EXPECT_EQ(classOf(4).format, TextureFormat::Bc1);
  EXPECT_EQ(classOf(1).format, TextureFormat::Bc1);
  EXPECT_EQ(classOf(1).colorSpace, ColorSpace::Linear);
  EXPECT_EQ(classOf(2).format, TextureFormat::Bc5);
  EXPECT_EQ(classOf(3).format, TextureFormat::Bc4);
  Result<std::vector<uint8_t>> bytes = serializePack(*scene);
  ASSERT_TRUE(bytes) << bytes.error().message;
  Result<Scene> back = parsePack(bytes->data(), bytes->size(), "helmet.vbp");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->textureClasses, scene->textureClasses);
}

TEST(GltfTextures, TextureSettingsTestSamplersMatchTheFile) {
  const fs::path path = assetPath("TextureSettingsTest/glTF/TextureSettingsTest.gltf");
  REQUIRE_ASSET(path);
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  const json doc = json::parse(std::ifstream(path));
  ASSERT_EQ(s->materials.size(), doc["materials"].size());
  auto wrap = [](int gl) {
    return gl == 33071 ? WrapMode::ClampToEdge : gl == 33648 ? WrapMode::MirroredRepeat : WrapMode::Repeat;
  };
  size_t checked = 0;
  for (size_t i = 0; i < s->materials.size(); ++i) {
    const json& jm = doc["materials"][i];
    EXPECT_EQ(s->materials[i].doubleSided, jm.value("doubleSided", false)) << i;
    if (!jm["pbrMetallicRoughness"].contains("baseColorTexture")) continue;
    const int texture = jm["pbrMetallicRoughness"]["baseColorTexture"]["index"];
    const json& sampler = doc["samplers"][doc["textures"][size_t(texture)]["sampler"].get<size_t>()];
    const TextureRef& ref = s->materials[i].baseColorTexture;
    EXPECT_EQ(ref.texture, texture);
    EXPECT_EQ(ref.sampler.wrapS, wrap(sampler.value("wrapS", 10497))) << i;
    EXPECT_EQ(ref.sampler.wrapT, wrap(sampler.value("wrapT", 10497))) << i;
    EXPECT_EQ(ref.sampler.minFilter, TextureFilter::Nearest);  // 9986 NEAREST_MIPMAP_LINEAR
    EXPECT_EQ(ref.sampler.mipFilter, MipFilter::Linear);
    ++checked;
  }
  EXPECT_GE(checked, 8u);
}

TEST(GltfTextures, MultiUvAndNormalTangentMirrorTestsHaveTheirStreams) {
  const fs::path multi = assetPath("MultiUVTest/glTF/MultiUVTest.gltf");
  const fs::path mirror = assetPath("NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf");
  REQUIRE_ASSET(multi);
  REQUIRE_ASSET(mirror);
  Result<ImportedScene> a = importGltfScene(multi.string());
  ASSERT_TRUE(a) << a.error().message;
  const MeshSource& am = a->meshes[0].source;
  EXPECT_EQ(am.uvs1.size(), am.positions.size());
  EXPECT_EQ(am.tangents.size(), am.positions.size());
  EXPECT_EQ(a->materials[0].baseColorTexture.texCoord, 0u);
  EXPECT_EQ(a->materials[0].emissiveTexture.texCoord, 1u);  // uv1.png on TEXCOORD_1
  EXPECT_EQ(a->materials[0].emissiveTexture.uri, "uv1.png");

  Result<ImportedScene> b = importGltfScene(mirror.string());
  ASSERT_TRUE(b) << b.error().message;
  const MeshSource& bm = b->meshes[0].source;
  ASSERT_EQ(bm.tangents.size(), bm.positions.size());
  size_t left = 0, right = 0;
  for (const glm::vec4& t : bm.tangents) (t.w < 0.0f ? left : right)++;
  EXPECT_GT(left, 0u);  // the asset mirrors uvs on half of each shape: both handednesses occur
  EXPECT_GT(right, 0u);
  const Material& m = b->materials[0];
  EXPECT_EQ(m.occlusionTexture.image, m.metallicRoughnessTexture.image);  // one ORM image
  Result<Scene> scene = buildImportedScene(*b);
  ASSERT_TRUE(scene) << scene.error().message;
  SKIP_WITHOUT_OIIO();  // what follows bakes the images
  Status baked = bakeTextures(*b, {64}, &scene.value());
  ASSERT_TRUE(baked) << baked.error().message;
  EXPECT_EQ(scene->textures.size(), 3u);  // ORM shared by occlusion and metallic-roughness (both linear)
  EXPECT_EQ(scene->materials[0].occlusionTexture.baked, scene->materials[0].metallicRoughnessTexture.baked);
}

TEST(GltfTextures, TextureCoordinateTestAndEmbeddedFoxImage) {
  const fs::path coords = assetPath("TextureCoordinateTest/glTF/TextureCoordinateTest.gltf");
  const fs::path fox = assetPath("Fox/glTF-Binary/Fox.glb");
  REQUIRE_ASSET(coords);
  REQUIRE_ASSET(fox);
  Result<ImportedScene> a = importGltfScene(coords.string());
  ASSERT_TRUE(a) << a.error().message;
  size_t textured = 0;
  for (const Material& m : a->materials) {
    if (m.baseColorTexture.image < 0) continue;
    ++textured;
    EXPECT_EQ(m.baseColorTexture.uri, "TextureCoordinateTemplate.png");
    EXPECT_EQ(m.baseColorTexture.texCoord, 0u);
  }
  EXPECT_GT(textured, 0u);
  for (const ImportedMesh& mesh : a->meshes) {
    if (a->materials[mesh.material].baseColorTexture.image < 0) continue;  // untextured meshes may lack uvs
    EXPECT_EQ(mesh.source.uvs.size(), mesh.source.positions.size()) << mesh.source.name;
  }
  Result<ImportedScene> f = importGltfScene(fox.string());
  ASSERT_TRUE(f) << f.error().message;
  ASSERT_EQ(f->images.size(), 1u);
  EXPECT_TRUE(f->images[0].path.empty());
  Result<Scene> scene = buildImportedScene(*f);
  ASSERT_TRUE(scene);
  SKIP_WITHOUT_OIIO();  // what follows bakes the images
  Status baked = bakeTextures(*f, {64}, &scene.value());
  ASSERT_TRUE(baked) << baked.error().message;
  ASSERT_EQ(scene->textures.size(), 1u);
  EXPECT_EQ(scene->textures[0].colorSpace, ColorSpace::Srgb);
}

}  // namespace
}  // namespace visbuf
