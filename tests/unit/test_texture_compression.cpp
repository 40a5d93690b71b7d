// Block-compressed textures (texture_bake.h step 5, scene/texture.h TextureFormat): BC1 / BC3 / BC4 / BC5 round
// trips against the float source with stated bounds, the block decoder against libsquish's and against the
// format's formulas, the class byte layout of block formats (levels below 4x4 are one block), the format chosen
// per slot use, the same bytes at any thread count, and a BC bake of a sample asset through the pack and back.
#include <gtest/gtest.h>
#include <squish.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "../build_config.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/asset/texture_bake.h"

namespace visbuf {
namespace {

// A float test image with what texture blocks meet: smooth gradients in every channel, a hard diagonal edge and
// mild noise (seeded), values in [0, 1].
LinearImage testImage(uint32_t size, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> noise(-0.03f, 0.03f);
  LinearImage image;
  image.width = image.height = size;
  image.rgba.resize(size_t(size) * size * 4);
  for (uint32_t y = 0; y < size; ++y) {
    for (uint32_t x = 0; x < size; ++x) {
      const float u = (float(x) + 0.5f) / float(size), v = (float(y) + 0.5f) / float(size);
      const float edge = x + y < size ? 0.0f : 0.35f;
      const float value[4] = {0.1f + 0.6f * u + edge, 0.8f - 0.5f * v, 0.3f + 0.4f * u * v + edge * 0.5f,
                              0.2f + 0.7f * v};
      for (int c = 0; c < 4; ++c)
        image.rgba[(size_t(y) * size + x) * 4 + size_t(c)] = std::clamp(value[c] + noise(rng), 0.0f, 1.0f);
    }
  }
  return image;
}

struct ChannelError {
  double rms = 0.0;  // in 8-bit code units
  double max = 0.0;
};

// Error of decoded RGBA8 against the float source in the encoded domain (sRGB codes for RGB of an sRGB image),
// per channel.
std::vector<ChannelError> errorAgainstSource(const std::vector<uint8_t>& decoded, const LinearImage& source,
                                             ColorSpace colorSpace) {
  std::vector<ChannelError> e(4);
  std::vector<double> sum(4, 0.0);
  const size_t texels = size_t(source.width) * source.height;
  for (size_t i = 0; i < texels; ++i) {
    for (size_t c = 0; c < 4; ++c) {
      double reference = source.rgba[i * 4 + c];
      if (colorSpace == ColorSpace::Srgb && c < 3) reference = linearToSrgb(float(reference));
      const double d = std::abs(decoded[i * 4 + c] - 255.0 * reference);
      sum[c] += d * d;
      e[c].max = std::max(e[c].max, d);
    }
  }
  for (size_t c = 0; c < 4; ++c) e[c].rms = std::sqrt(sum[c] / double(texels));
  return e;
}

TEST(TextureCompression, RoundTripOfEachFormatStaysWithinItsBound) {
  // Bounds in 8-bit codes, measured against the float source (the RGBA8 rounding included): BC1 / BC3 colour
  // are two 5:6:5 endpoints and 4 interpolants per 4x4 block; BC4 / BC5 channels two 8-bit endpoints and 8
  // interpolants. Both bounds are 1.5x the worst channel libsquish 1.15 reaches on this image (range fit, linear:
  // RMS 4.8 / max 20.6 codes for BC1 colour, 1.3 / 8.4 for BC4 / BC5); the largest errors are the blocks on the
  // hard edge, where one line in colour space must stand for two colours.
  struct Case {
    TextureFormat format;
    ColorSpace colorSpace;
    std::vector<size_t> channels;  // the channels the format keeps
    double rms, max;
  };
  const Case cases[] = {
      {TextureFormat::Bc1, ColorSpace::Srgb, {0, 1, 2}, 7.2, 31.0},
      {TextureFormat::Bc1, ColorSpace::Linear, {0, 1, 2}, 7.2, 31.0},
      {TextureFormat::Bc3, ColorSpace::Srgb, {0, 1, 2, 3}, 7.2, 31.0},
      {TextureFormat::Bc4, ColorSpace::Linear, {0}, 2.0, 12.6},
      {TextureFormat::Bc5, ColorSpace::Linear, {0, 1}, 2.0, 12.6},
  };
  const LinearImage source = testImage(64, 7);
  for (const Case& k : cases) {
    for (TextureQuality quality : {TextureQuality::Fast, TextureQuality::Normal}) {
      SCOPED_TRACE(std::string(textureFormatName(k.format)) + " " + textureQualityName(quality) +
                   (k.colorSpace == ColorSpace::Srgb ? " sRGB" : " linear"));
      const std::vector<uint8_t> rgba = encodeRgba8(source, k.colorSpace);
      const std::vector<uint8_t> blocks = compressBlocks(rgba.data(), 64, 64, k.format, quality);
      ASSERT_EQ(blocks.size(), textureImageBytes(k.format, 64, 64));
      ASSERT_EQ(blocks.size(), 16u * 16u * textureFormatUnitBytes(k.format));
      const std::vector<uint8_t> decoded = decodeTextureImage(blocks.data(), 64, 64, k.format);
      const std::vector<ChannelError> e = errorAgainstSource(decoded, source, k.colorSpace);
      std::printf("%s %s %s:", textureFormatName(k.format), textureQualityName(quality),
                  k.colorSpace == ColorSpace::Srgb ? "sRGB" : "linear");
      for (size_t c : k.channels) std::printf("  ch%zu RMS %.2f max %.1f", c, e[c].rms, e[c].max);
      std::printf("\n");
      for (size_t c : k.channels) {
        EXPECT_LE(e[c].rms, k.rms) << "channel " << c;
        EXPECT_LE(e[c].max, k.max) << "channel " << c;
      }
      // The channels a format does not store decode as Vulkan reads them: 0 for missing colour, 1 for alpha.
      const bool noGreen = k.format == TextureFormat::Bc4;
      const bool noBlue = noGreen || k.format == TextureFormat::Bc5;
      const bool noAlpha = k.format != TextureFormat::Bc3;
      for (size_t i = 0; i < decoded.size(); i += 4) {
        ASSERT_TRUE(!noGreen || decoded[i + 1] == 0) << "texel " << i / 4;
        ASSERT_TRUE(!noBlue || decoded[i + 2] == 0) << "texel " << i / 4;
        ASSERT_TRUE(!noAlpha || decoded[i + 3] == 255) << "texel " << i / 4;
      }
    }
  }
}

TEST(TextureCompression, BlockDecoderAgreesWithLibsquishAndTheFormulas) {
  // BC1 / BC3: libsquish's own decoder is an independent implementation; interpolants may differ by rounding.
  const LinearImage source = testImage(32, 3);
  const std::vector<uint8_t> rgba = encodeRgba8(source, ColorSpace::Linear);
  for (const auto& [format, flags] : {std::pair{TextureFormat::Bc1, squish::kDxt1}, std::pair{TextureFormat::Bc3, squish::kDxt5}}) {
    const std::vector<uint8_t> blocks = compressBlocks(rgba.data(), 32, 32, format, TextureQuality::Normal);
    std::vector<uint8_t> theirs(32 * 32 * 4);
    squish::DecompressImage(theirs.data(), 32, 32, blocks.data(), flags);
    const std::vector<uint8_t> ours = decodeTextureImage(blocks.data(), 32, 32, format);
    int worst = 0;  // RGB, and BC3's alpha (BC1 is read as the RGB format: alpha 1)
    for (size_t i = 0; i < ours.size(); ++i)
      if (i % 4 != 3 || format == TextureFormat::Bc3) worst = std::max(worst, std::abs(int(ours[i]) - int(theirs[i])));
    EXPECT_LE(worst, 1) << textureFormatName(format);
    // The unrounded decode (the judge's texels): the 8-bit one is it rounded at the endpoints and the interpolants.
    const std::vector<double> exact = decodeTextureImageExact(blocks.data(), 32, 32, format);
    double off = 0.0;
    for (size_t i = 0; i < ours.size(); ++i) off = std::max(off, std::abs(exact[i] * 255.0 - double(ours[i])));
    EXPECT_LE(off, 1.0) << textureFormatName(format);
  }
  // BC4, both modes, against the interpolation formulas of the format (exact values, rounded to 8 bits).
  auto bc4Block = [](uint8_t a, uint8_t b) {
    std::vector<uint8_t> block(8, 0);
    block[0] = a;
    block[1] = b;
    uint64_t bits = 0;
    for (uint64_t i = 0; i < 16; ++i) bits |= (i % 8) << (3 * i);  // texel i uses index i mod 8
    for (int k = 0; k < 6; ++k) block[size_t(2 + k)] = uint8_t(bits >> (8 * k));
    return block;
  };
  const std::vector<uint8_t> eight = decodeTextureImage(bc4Block(200, 60).data(), 4, 4, TextureFormat::Bc4);
  const std::vector<uint8_t> six = decodeTextureImage(bc4Block(60, 200).data(), 4, 4, TextureFormat::Bc4);
  for (int i = 0; i < 16; ++i) {
    const int index = i % 8;
    const double e8 = index == 0 ? 200 : index == 1 ? 60 : ((7 - (index - 1)) * 200.0 + (index - 1) * 60.0) / 7.0;
    const double e6 = index == 0 ? 60 : index == 1 ? 200 : index == 6 ? 0 : index == 7 ? 255
                      : ((5 - (index - 1)) * 60.0 + (index - 1) * 200.0) / 5.0;
    EXPECT_LE(std::abs(eight[size_t(i) * 4] - e8), 0.5) << "8-value mode, index " << index;
    EXPECT_LE(std::abs(six[size_t(i) * 4] - e6), 0.5) << "6-value mode, index " << index;
    EXPECT_NEAR(decodeTextureImageExact(bc4Block(200, 60).data(), 4, 4, TextureFormat::Bc4)[size_t(i) * 4], e8 / 255.0,
                1e-12);
    EXPECT_NEAR(decodeTextureImageExact(bc4Block(60, 200).data(), 4, 4, TextureFormat::Bc4)[size_t(i) * 4], e6 / 255.0,
                1e-12);
  }
}

TEST(TextureCompression, LevelsBelowFourTexelsAreOneWholeBlock) {
  // 1x1 and 2x2 levels: one block each, fitted to the texels inside the level only. The 2x2 texels lie on one
  // line in colour space, evenly spaced (what a block's endpoints and interpolants can hold), so the error is the
  // endpoints' quantisation: 5:6:5 for BC1 / BC3 colour (255 / 31 plus rounding), 8 bits for BC4 / BC5 and BC3
  // alpha, where 4 values are also within half a step of 255 / 7 of the 8 interpolants.
  for (uint32_t side : {1u, 2u}) {
    std::vector<uint8_t> rgba;
    for (uint32_t i = 0; i < side * side; ++i) {
      const uint8_t t = uint8_t(side == 1 ? 1 : i);
      for (uint8_t v : {uint8_t(40 + 51 * t), uint8_t(60 + 42 * t), uint8_t(201 - 39 * t), uint8_t(255 - 30 * t)})
        rgba.push_back(v);
    }
    for (TextureFormat f : {TextureFormat::Bc1, TextureFormat::Bc3, TextureFormat::Bc4, TextureFormat::Bc5}) {
      const std::vector<uint8_t> blocks = compressBlocks(rgba.data(), side, side, f, TextureQuality::Fast);
      EXPECT_EQ(blocks.size(), textureFormatUnitBytes(f));
      const std::vector<uint8_t> decoded = decodeTextureImage(blocks.data(), side, side, f);
      ASSERT_EQ(decoded.size(), size_t(side) * side * 4);
      const size_t channels = f == TextureFormat::Bc4 ? 1 : f == TextureFormat::Bc5 ? 2 : f == TextureFormat::Bc1 ? 3 : 4;
      for (size_t i = 0; i < decoded.size(); i += 4) {
        for (size_t c = 0; c < channels; ++c) {
          const bool eightBit = f == TextureFormat::Bc4 || f == TextureFormat::Bc5 || c == 3;
          const double bound = eightBit ? 255.0 / 14.0 : 255.0 / 31.0 + 1.0;
          EXPECT_LE(std::abs(decoded[i + c] - rgba[i + c]), bound)
              << textureFormatName(f) << " " << side << "x" << side << " texel " << i / 4 << " channel " << c;
        }
      }
    }
  }
}

TEST(TextureCompression, ClassByteLayoutUsesWholeBlocks) {
  TextureClass c;
  c.size = 8;
  c.layers = 3;
  c.mipCount = TextureClass::mipCountFor(8);
  ASSERT_EQ(c.mipCount, 4u);
  c.format = TextureFormat::Rgba8;
  EXPECT_EQ(c.layerBytes(0), 256u);
  EXPECT_EQ(c.layerBytes(3), 4u);
  EXPECT_EQ(c.totalBytes(), 3u * (256 + 64 + 16 + 4));
  // BC1 / BC4: 8 bytes a 4x4 block; 8x8 is 2x2 blocks, 4x4 one block, and 2x2 and 1x1 one whole block each.
  for (TextureFormat f : {TextureFormat::Bc1, TextureFormat::Bc4}) {
    c.format = f;
    EXPECT_EQ(c.layerBytes(0), 32u);
    EXPECT_EQ(c.layerBytes(1), 8u);
    EXPECT_EQ(c.layerBytes(2), 8u);
    EXPECT_EQ(c.layerBytes(3), 8u);
    EXPECT_EQ(c.offset(0, 2), 64u);
    EXPECT_EQ(c.offset(1, 0), 96u);
    EXPECT_EQ(c.offset(3, 1), 96u + 24u + 24u + 8u);
    EXPECT_EQ(c.totalBytes(), 3u * (32 + 8 + 8 + 8));
  }
  for (TextureFormat f : {TextureFormat::Bc3, TextureFormat::Bc5}) {
    c.format = f;
    EXPECT_EQ(c.layerBytes(0), 64u);
    EXPECT_EQ(c.layerBytes(3), 16u);
    EXPECT_EQ(c.totalBytes(), 3u * (64 + 16 + 16 + 16));
  }
  EXPECT_EQ(textureImageBytes(TextureFormat::Bc1, 2048, 2048), 2048u * 2048u / 2u);
  EXPECT_EQ(textureImageBytes(TextureFormat::Bc5, 2048, 2048), 2048u * 2048u);
}

TEST(TextureCompression, FormatFollowsTheSlotsThatUseTheImage) {
  constexpr TextureSlotMask base = 1, mr = 2, normal = 4, occlusion = 8, emissive = 16;
  const TextureEncoding bc = TextureEncoding::Bc;
  EXPECT_EQ(chooseTextureFormat(bc, base, ColorSpace::Srgb, true), TextureFormat::Bc1);
  EXPECT_EQ(chooseTextureFormat(bc, base, ColorSpace::Srgb, false), TextureFormat::Bc3);
  EXPECT_EQ(chooseTextureFormat(bc, emissive, ColorSpace::Srgb, false), TextureFormat::Bc1);  // alpha unused
  EXPECT_EQ(chooseTextureFormat(bc, base | emissive, ColorSpace::Srgb, false), TextureFormat::Bc3);
  EXPECT_EQ(chooseTextureFormat(bc, normal, ColorSpace::Linear, true), TextureFormat::Bc5);
  EXPECT_EQ(chooseTextureFormat(bc, occlusion, ColorSpace::Linear, true), TextureFormat::Bc4);
  EXPECT_EQ(chooseTextureFormat(bc, mr, ColorSpace::Linear, true), TextureFormat::Bc1);
  EXPECT_EQ(chooseTextureFormat(bc, mr | occlusion, ColorSpace::Linear, true), TextureFormat::Bc1);  // ORM
  EXPECT_EQ(chooseTextureFormat(bc, mr | normal, ColorSpace::Linear, true), TextureFormat::Bc1);  // z is read
  for (TextureSlotMask m : {base, mr, normal, occlusion, emissive})
    EXPECT_EQ(chooseTextureFormat(TextureEncoding::Rgba8, m, ColorSpace::Linear, false), TextureFormat::Rgba8);
}

TEST(TextureCompression, FormatsFoldWhenTheClassesWouldNotFitTheBindings) {
  // Every size 1..2048 with all five (colour space, format) pairs: 60 classes, against 24 bindings.
  std::vector<TextureClassKey> all;
  for (uint32_t size = 1; size <= 2048; size *= 2) {
    all.push_back({size, ColorSpace::Srgb, TextureFormat::Bc1});
    all.push_back({size, ColorSpace::Srgb, TextureFormat::Bc3});
    all.push_back({size, ColorSpace::Linear, TextureFormat::Bc1});
    all.push_back({size, ColorSpace::Linear, TextureFormat::Bc4});
    all.push_back({size, ColorSpace::Linear, TextureFormat::Bc5});
  }
  EXPECT_EQ(countTextureClasses(all), 60u);
  std::vector<TextureClassKey> fitted = all;
  EXPECT_EQ(fitTextureClassFormats(fitted, 24), 24u);  // BC4, BC5 -> BC1, sRGB BC1 -> BC3: 12 x 2
  for (const TextureClassKey& k : fitted)
    EXPECT_EQ(k.format, k.colorSpace == ColorSpace::Srgb ? TextureFormat::Bc3 : TextureFormat::Bc1);
  // Only as far as needed: 48 fit once BC4 has folded, and nothing changes when everything fits.
  fitted = all;
  EXPECT_EQ(fitTextureClassFormats(fitted, 48), 48u);
  for (size_t i = 0; i < all.size(); ++i)
    EXPECT_EQ(fitted[i].format, all[i].format == TextureFormat::Bc4 ? TextureFormat::Bc1 : all[i].format);
  fitted = all;
  EXPECT_EQ(fitTextureClassFormats(fitted, 60), 60u);
  for (size_t i = 0; i < all.size(); ++i) EXPECT_EQ(fitted[i].format, all[i].format);
  // 257 layers of one key are two classes (256 layers each at most).
  EXPECT_EQ(countTextureClasses(std::vector<TextureClassKey>(257, {64, ColorSpace::Linear, TextureFormat::Bc5})), 2u);
}

TEST(TextureCompression, SameBytesWithOneThreadAndWithSeveral) {
  const LinearImage source = testImage(256, 11);
  const std::vector<uint8_t> rgba = encodeRgba8(source, ColorSpace::Srgb);
  tbb::task_arena one(1), four(4);
  for (TextureFormat f : {TextureFormat::Bc1, TextureFormat::Bc3, TextureFormat::Bc4, TextureFormat::Bc5}) {
    std::vector<uint8_t> a, b;
    one.execute([&] { a = compressBlocks(rgba.data(), 256, 256, f, TextureQuality::Fast); });
    four.execute([&] { b = compressBlocks(rgba.data(), 256, 256, f, TextureQuality::Fast); });
    EXPECT_EQ(a, b) << textureFormatName(f);
  }
  // A whole bake: images in parallel, levels in parallel, classes assembled in order. It decodes PNG images: a build
  // without OpenImageIO ran the block compressor's half of this test only.
  SKIP_WITHOUT_OIIO();
  const auto path = test::assetPath("NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf");
  Result<ImportedScene> imported = importGltfScene(path.string());
  ASSERT_TRUE(imported) << imported.error().message;
  auto bake = [&](size_t threads) -> Scene {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Result<Scene> scene = buildImportedScene(*imported);
    EXPECT_TRUE(scene);
    TextureBakeOptions options;
    options.maxTextureSize = 256;
    Status s = bakeTextures(*imported, options, &scene.value());
    EXPECT_TRUE(s) << s.error().message;
    return std::move(scene.value());
  };
  const Scene serial = bake(1), parallel = bake(4);
  ASSERT_FALSE(serial.textureClasses.empty());
  EXPECT_EQ(serial.textures, parallel.textures);
  EXPECT_EQ(serial.textureClasses, parallel.textureClasses);
}

// The sample asset baked with BC and with RGBA8: the formats follow the slots, the pack keeps the BC classes
// byte for byte, and every level of every BC layer is the compression of the RGBA8 bake's same level.
TEST(TextureCompression, BcBakeRoundTripsThroughThePackAndMatchesTheRgba8Bake) {
  SKIP_WITHOUT_OIIO();
  const auto path = test::assetPath("NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf");
  Result<ImportedScene> imported = importGltfScene(path.string());
  ASSERT_TRUE(imported) << imported.error().message;
  auto bake = [&](TextureEncoding encoding) -> Result<Scene> {
    Result<Scene> scene = buildImportedScene(*imported);
    if (!scene) return scene.error();
    TextureBakeOptions options;
    options.maxTextureSize = 128;
    options.encoding = encoding;
    if (Status s = bakeTextures(*imported, options, &scene.value()); !s) return s.error();
    return scene;
  };
  Result<Scene> bc = bake(TextureEncoding::Bc), rgba8 = bake(TextureEncoding::Rgba8);
  ASSERT_TRUE(bc) << bc.error().message;
  ASSERT_TRUE(rgba8) << rgba8.error().message;
  ASSERT_EQ(bc->textures.size(), 3u);
  const Material& m = bc->materials[0];
  const auto formatOf = [&](const TextureRef& ref) {
    return bc->textureClasses[bc->textures[size_t(ref.baked)].sizeClass].format;
  };
  EXPECT_EQ(formatOf(m.normalTexture), TextureFormat::Bc5);
  EXPECT_EQ(formatOf(m.metallicRoughnessTexture), TextureFormat::Bc1);  // the ORM image: three channels read
  // Base colour: BC1 when the RGBA8 bake's alpha is all 255, else BC3.
  const Texture& baseRgba8 = rgba8->textures[size_t(rgba8->materials[0].baseColorTexture.baked)];
  const TextureClass& baseClass = rgba8->textureClasses[baseRgba8.sizeClass];
  bool opaque = true;
  for (uint64_t i = baseClass.offset(0, baseRgba8.layer) + 3; i < baseClass.offset(0, baseRgba8.layer + 1); i += 4)
    opaque = opaque && baseClass.texels[i] == 255;
  EXPECT_EQ(formatOf(m.baseColorTexture), opaque ? TextureFormat::Bc1 : TextureFormat::Bc3);

  Result<std::vector<uint8_t>> bytes = serializePack(*bc);
  ASSERT_TRUE(bytes) << bytes.error().message;
  Result<Scene> back = parsePack(bytes->data(), bytes->size(), "bc.vbp");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->textures, bc->textures);
  EXPECT_EQ(back->textureClasses, bc->textureClasses);

  // Mips first, then each level compressed: every BC level is exactly the compression of the RGBA8 bake's level.
  for (size_t t = 0; t < bc->textures.size(); ++t) {
    const TextureClass& c = bc->textureClasses[bc->textures[t].sizeClass];
    const TextureClass& r = rgba8->textureClasses[rgba8->textures[t].sizeClass];
    ASSERT_EQ(c.size, r.size);
    ASSERT_EQ(r.format, TextureFormat::Rgba8);
    for (uint32_t mip = 0; mip < c.mipCount; ++mip) {
      const uint32_t side = c.mipSize(mip);
      const std::vector<uint8_t> expected = compressBlocks(r.texels.data() + r.offset(mip, rgba8->textures[t].layer),
                                                           side, side, c.format, TextureQuality::Fast);
      const uint8_t* actual = c.texels.data() + c.offset(mip, bc->textures[t].layer);
      ASSERT_EQ(expected.size(), c.layerBytes(mip));
      EXPECT_TRUE(std::equal(expected.begin(), expected.end(), actual))
          << "texture " << t << " (" << textureFormatName(c.format) << ") mip " << mip;
    }
  }
}

// --normal-map-size: the normal-only image keeps the levels from that size down -- byte for byte the lower levels
// of the uncapped bake (the same box-filtered chain, compressed level by level) -- and no other image shrinks.
TEST(TextureCompression, NormalMapSizeKeepsTheUncappedBakesLowerLevels) {
  SKIP_WITHOUT_OIIO();
  const auto path = test::assetPath("NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf");
  Result<ImportedScene> imported = importGltfScene(path.string());
  ASSERT_TRUE(imported) << imported.error().message;
  auto bake = [&](uint32_t normalMapSize) -> Result<Scene> {
    Result<Scene> scene = buildImportedScene(*imported);
    if (!scene) return scene.error();
    TextureBakeOptions options;
    options.maxTextureSize = 128;
    options.maxNormalMapSize = normalMapSize;
    if (Status s = bakeTextures(*imported, options, &scene.value()); !s) return s.error();
    return scene;
  };
  Result<Scene> full = bake(0), capped = bake(32);
  ASSERT_TRUE(full && capped);
  ASSERT_EQ(full->textures.size(), capped->textures.size());
  const int normal = full->materials[0].normalTexture.baked;
  ASSERT_GE(normal, 0);
  for (size_t t = 0; t < full->textures.size(); ++t) {
    const Texture& a = full->textures[t];
    const Texture& b = capped->textures[t];
    const TextureClass& ca = full->textureClasses[a.sizeClass];
    const TextureClass& cb = capped->textureClasses[b.sizeClass];
    ASSERT_EQ(ca.size, 128u);
    ASSERT_EQ(cb.size, int(t) == normal ? 32u : 128u) << "texture " << t;
    ASSERT_EQ(ca.format, cb.format);
    const uint32_t skip = ca.mipCount - cb.mipCount;
    for (uint32_t mip = 0; mip < cb.mipCount; ++mip)
      EXPECT_TRUE(std::equal(cb.texels.begin() + int64_t(cb.offset(mip, b.layer)),
                             cb.texels.begin() + int64_t(cb.offset(mip, b.layer) + cb.layerBytes(mip)),
                             ca.texels.begin() + int64_t(ca.offset(mip + skip, a.layer))))
          << "texture " << t << " level " << mip;
  }
  TextureBakeOptions bad;
  bad.maxNormalMapSize = 48;
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene);
  EXPECT_FALSE(bakeTextures(*imported, bad, &scene.value()));
}

}  // namespace
}  // namespace visbuf
