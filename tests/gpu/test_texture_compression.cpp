// Block-compressed texture classes on the GPU (scene/gpu_textures.cpp, shaders/material.glsl): a textured sample
// asset baked with BC textures renders within 38 dB PSNR of its RGBA8 bake, and the chunked upload puts every
// byte where the class says, both as BC blocks and decompressed to RGBA8 (a device without textureCompressionBC),
// through a staging buffer far smaller than the class. Validation layers on: any message fails.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <vector>

#include "gpu_test_util.h"
#include "../unit/test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/asset/texture_bake.h"
#include "visbuf/gpu/check.h"
#include "visbuf/render/renderer.h"
#include "visbuf/scene/gpu_scene.h"

namespace visbuf {
namespace {

Result<Scene> bakeAsset(const std::string& relative, TextureEncoding encoding) {
  Result<ImportedScene> imported = importGltfScene(test::assetPath(relative).string());
  if (!imported) return imported.error();
  Result<Scene> scene = buildImportedScene(*imported);
  if (!scene) return scene.error();
  TextureBakeOptions options;
  options.encoding = encoding;
  if (Status s = bakeTextures(*imported, options, &scene.value()); !s) return s.error();
  return scene;
}

GPU_TEST(TextureCompressionGpu, BcBakeRendersWithin38DbOfTheRgba8Bake) {
  SKIP_WITHOUT_OIIO();  // the asset's textures are PNG images
  ASSERT_TRUE(dev.textureCompressionBC()) << "the test device samples BC formats (lavapipe does)";
  const std::string asset = "NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf";
  Result<Scene> bc = bakeAsset(asset, TextureEncoding::Bc), rgba8 = bakeAsset(asset, TextureEncoding::Rgba8);
  ASSERT_TRUE(bc) << bc.error().message;
  ASSERT_TRUE(rgba8) << rgba8.error().message;
  bool twoChannelNormals = false;
  for (const TextureClass& c : bc->textureClasses) twoChannelNormals |= c.format == TextureFormat::Bc5;
  ASSERT_TRUE(twoChannelNormals) << "the asset's normal map bakes to BC5 (z rebuilt in the shader)";
  const uint32_t w = 512, h = 512;
  auto render = [&](const Scene& s) -> Result<FrameResult> {
    auto r = Renderer::create(dev, s, {.width = w, .height = h});
    if (!r) return r.error();
    return (*r)->renderFrame(s.defaultCamera, FrameOptions{});
  };
  Result<FrameResult> a = render(*bc), b = render(*rgba8);
  ASSERT_TRUE(a) << a.error().message;
  ASSERT_TRUE(b) << b.error().message;
  const ImageError e = compareColor(a->color, b->color);
  std::printf("NormalTangentMirrorTest bc vs rgba8: PSNR %.1f dB, max %.3f, mean %.2e, %.2f%% pixels > 1/255\n", e.psnr,
              e.maxAbs, e.meanAbs, 100.0 * e.differingFraction);
  EXPECT_GE(e.psnr, 38.0);
  test::saveOnFailure("texture_compression_bc_vs_rgba8", *a, *b);
}

// Reads every level and layer of a sampled texture class image back into the class's own layout (mip-major; BC
// images as blocks, a decompressed one as RGBA8).
std::vector<uint8_t> readBack(gpu::Device& dev, const gpu::Image& image, const TextureClass& c, bool rgba8) {
  TextureClass layout = c;
  if (rgba8) layout.format = TextureFormat::Rgba8;
  gpu::Buffer buffer(dev, layout.totalBytes(), VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
  std::vector<VkBufferImageCopy> regions;
  for (uint32_t m = 0; m < c.mipCount; ++m) {
    VkBufferImageCopy r{};
    r.bufferOffset = layout.offset(m, 0);
    r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, m, 0, c.layers};
    r.imageExtent = {c.mipSize(m), c.mipSize(m), 1};
    regions.push_back(r);
  }
  VkCommandBuffer cmd = dev.beginOneShot();
  gpu::imageBarrier(cmd, image, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_SHADER_READ_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
                    VK_ACCESS_2_TRANSFER_READ_BIT);
  vkCmdCopyImageToBuffer(cmd, image.handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer.handle(),
                         uint32_t(regions.size()), regions.data());
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                     VK_ACCESS_2_HOST_READ_BIT);
  dev.submitOneShot(cmd);
  std::vector<uint8_t> out(layout.totalBytes());
  std::memcpy(out.data(), buffer.mapped(), out.size());
  return out;
}

GPU_TEST(TextureCompressionGpu, ChunkedUploadPlacesEveryBlockAndDecompressesWhereAsked) {
  // 512^2 x 3 layers: 1 MiB of mip 0 per layer in RGBA8, so a 64 KiB staging buffer takes many batches and cuts
  // each large level into bands of block rows.
  for (TextureFormat f : {TextureFormat::Bc1, TextureFormat::Bc3, TextureFormat::Bc4, TextureFormat::Bc5}) {
    TextureClass c;
    c.size = 512;
    c.layers = 3;
    c.mipCount = TextureClass::mipCountFor(c.size);
    c.format = f;
    c.colorSpace = f == TextureFormat::Bc1 ? ColorSpace::Srgb : ColorSpace::Linear;
    c.texels.resize(c.totalBytes());
    // Arbitrary blocks: every byte pattern is a valid BC block.
    uint32_t state = 12345u + uint32_t(f);
    for (uint8_t& b : c.texels) b = uint8_t((state = state * 1664525u + 1013904223u) >> 24);
    for (bool allowBc : {true, false}) {
      SCOPED_TRACE(std::string(textureFormatName(f)) + (allowBc ? " as BC" : " decompressed"));
      TextureUploadOptions options;
      options.allowBc = allowBc;
      options.stagingBytes = VkDeviceSize{64} << 10;
      options.extraUsage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
      TextureUpload up = uploadTextureClass(dev, c, options);
      EXPECT_EQ(up.decompressed, !allowBc);
      EXPECT_EQ(up.stagingBytes, 64u << 10) << "the staging buffer stays at the size asked for";
      const std::vector<uint8_t> got = readBack(dev, up.image, c, up.decompressed);
      if (!up.decompressed) {
        EXPECT_EQ(up.gpuBytes, c.totalBytes());
        EXPECT_TRUE(got == c.texels);
        continue;
      }
      TextureClass rgba8 = c;
      rgba8.format = TextureFormat::Rgba8;
      EXPECT_EQ(up.gpuBytes, rgba8.totalBytes());
      bool same = true;
      for (uint32_t m = 0; m < c.mipCount && same; ++m) {
        for (uint32_t l = 0; l < c.layers && same; ++l) {
          const std::vector<uint8_t> expected =
              decodeTextureImage(c.texels.data() + c.offset(m, l), c.mipSize(m), c.mipSize(m), f);
          same = std::memcmp(expected.data(), got.data() + rgba8.offset(m, l), expected.size()) == 0;
          EXPECT_TRUE(same) << "mip " << m << " layer " << l;
        }
      }
    }
  }
}

}  // namespace
}  // namespace visbuf
