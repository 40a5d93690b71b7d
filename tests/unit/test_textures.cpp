// Tests for texture baking (engine/asset/texture_bake.h) and the material / texture / tangent import of
// importGltfScene: mip chains against a double-precision box filter (sRGB-correct), size rules, corrupt images,
// a generated glTF fixture that sets every material field, and the sample assets.
#include <gtest/gtest.h>

#include <algorithm>
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

std::vector<uint8_t> randomRgba(uint32_t width, uint32_t height, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> rgba(size_t(width) * height * 4);
  for (uint8_t& v : rgba) v = uint8_t(rng() & 0xFF);
  return rgba;
}

std::vector<uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string base64(const std::vector<uint8_t>& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t t = uint32_t(bytes[i]) << 16;
    if (i + 1 < bytes.size()) t |= uint32_t(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) t |= bytes[i + 2];
    for (size_t k = 0; k < 4; ++k) out += i + k <= bytes.size() ? kAlphabet[(t >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

// Writes PNGs with OpenImageIO at test time (no committed binaries); skips without OpenImageIO.
class TextureTest : public test::TempDirTest {
 protected:
  fs::path writePng(const std::string& name, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba) {
    const fs::path path = dir_ / name;
    Status s = writeRgba8Image(path.string(), width, height, rgba);
    if (!s && s.error().code == ErrorCode::Unsupported) {
      noOiio_ = true;
      return path;
    }
    EXPECT_TRUE(s) << s.error().message;
    return path;
  }
  std::vector<uint8_t> pngBytes(uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba) {
    return readBytes(writePng("tmp.png", width, height, rgba));
  }
  bool noOiio_ = false;
};

#define REQUIRE_OIIO()                                                          \
  do {                                                                          \
    if (noOiio_) GTEST_SKIP() << "built without OpenImageIO (VISBUF_WITH_OIIO)"; \
  } while (0)

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

// --- a generated glTF that sets every material field -----------------------------------------------------

class MaterialFixture : public TextureTest {
 protected:
  // One triangle (0,0,0) (1,0,0) (0,1,0), normal +Z, uv0 = xy, uv1 = xy / 2, tangent (1,0,0,1); used by a
  // plain node and by a mirrored one (scale -1 in x). Material 0 sets every field, material 1 none.
  fs::path write() {
    writePng("colour map.png", 8, 8, randomRgba(8, 8, 1));
    writePng("data.png", 4, 4, randomRgba(4, 4, 2));
    std::vector<uint8_t> embedded = readBytes(writePng("embedded.png", 4, 2, randomRgba(4, 2, 3)));
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

TEST_F(MaterialFixture, MissingExternalImageIsAClearError) {
  const fs::path path = write();
  REQUIRE_OIIO();
  fs::remove(dir_ / "data.png");
  Result<ImportedScene> imported = importGltfScene(path.string());
  ASSERT_TRUE(imported) << imported.error().message;  // import does not read pixels
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene);
  Status s = bakeTextures(*imported, {}, &scene.value());
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

// --- sample assets ------------------------------------------------------------------------------------

// DamagedHelmet is not redistributable: this test exists only when VISBUF_EXTRA_ASSETS has it.
EXTRA_ASSET_TEST(GltfTextures, DamagedHelmetHasFiveTexturesWithTheRightColourSpaces,
                 "DamagedHelmet/glTF-Binary/DamagedHelmet.glb") {
  Result<ImportedScene> imported = importGltfScene(asset.string());
  ASSERT_TRUE(imported) << imported.error().message;
  ASSERT_EQ(imported->materials.size(), 1u);
  const Material& m = imported->materials[0];
  EXPECT_EQ(m.emissive, glm::vec3(1.0f));
  for (const TextureRef* t : textureSlots(m)) EXPECT_GE(t->image, 0);
  ASSERT_EQ(imported->images.size(), 5u);
  for (const ImportedImage& image : imported->images) EXPECT_FALSE(image.bytes.empty());  // GLB bufferViews
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene) << scene.error().message;
  TextureBakeOptions options;
  options.maxTextureSize = 128;  // keeps the test fast; the 2048 originals are downscaled
  Status baked = bakeTextures(*imported, options, &scene.value());
  if (!baked && baked.error().code == ErrorCode::Unsupported) GTEST_SKIP() << baked.error().message;
  ASSERT_TRUE(baked) << baked.error().message;
  ASSERT_EQ(scene->textures.size(), 5u);
  const Material& bm = scene->materials[0];
  const auto slots = textureSlots(bm);
  for (size_t slot = 0; slot < slots.size(); ++slot) {
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
  Status baked = bakeTextures(*b, {64}, &scene.value());
  if (!baked && baked.error().code == ErrorCode::Unsupported) GTEST_SKIP() << baked.error().message;
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
  Status baked = bakeTextures(*f, {64}, &scene.value());
  if (!baked && baked.error().code == ErrorCode::Unsupported) GTEST_SKIP() << baked.error().message;
  ASSERT_TRUE(baked) << baked.error().message;
  ASSERT_EQ(scene->textures.size(), 1u);
  EXPECT_EQ(scene->textures[0].colorSpace, ColorSpace::Srgb);
}

}  // namespace
}  // namespace visbuf
