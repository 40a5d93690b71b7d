// Baked texture classes (scene/texture.h) to GPU images: one sampled 2D array per class, every mip level.
//
// The texels reach the image through one staging buffer of bounded size: the class is cut into pieces (a whole
// (mip, layer) image, or a band of its rows when one image is larger than the buffer; BC bands are whole block
// rows), as many pieces as fit are copied per submission, and the buffer is refilled only after that
// submission's copies have finished (submitOneShot waits). Host memory of the upload is then the staging buffer,
// whatever the class size. A BC class on a device without textureCompressionBC is decompressed band by band
// into the staging buffer as RGBA8.
#include <algorithm>
#include <cstring>

#include "visbuf/gpu/check.h"
#include "visbuf/scene/gpu_scene.h"

namespace visbuf {

namespace {

// A band of rows [row, row + rows) of layer `layer` at mip level `mip`.
struct Piece {
  uint32_t mip = 0, layer = 0, row = 0, rows = 0;
};

}  // namespace

VkFormat textureClassFormat(const TextureClass& c, bool decompressed) {
  const bool srgb = c.colorSpace == ColorSpace::Srgb;
  if (decompressed || c.format == TextureFormat::Rgba8)
    return srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM;
  switch (c.format) {
    case TextureFormat::Bc1: return srgb ? VK_FORMAT_BC1_RGB_SRGB_BLOCK : VK_FORMAT_BC1_RGB_UNORM_BLOCK;
    case TextureFormat::Bc3: return srgb ? VK_FORMAT_BC3_SRGB_BLOCK : VK_FORMAT_BC3_UNORM_BLOCK;
    case TextureFormat::Bc4: return VK_FORMAT_BC4_UNORM_BLOCK;
    case TextureFormat::Bc5: return VK_FORMAT_BC5_UNORM_BLOCK;
    case TextureFormat::Rgba8: break;
  }
  return VK_FORMAT_UNDEFINED;
}

TextureUpload uploadTextureClass(gpu::Device& device, const TextureClass& c, const TextureUploadOptions& options) {
  TextureUpload up;
  const bool bc = isBlockCompressed(c.format);
  up.decompressed = bc && !(options.allowBc && device.textureCompressionBC());
  const VkFormat format = textureClassFormat(c, up.decompressed);
  up.image = gpu::Image(device, format, c.size, c.size, VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | options.extraUsage,
                        VK_IMAGE_ASPECT_COLOR_BIT, c.mipCount, c.layers);
  // Rows of a band: whole 4-row block rows for BC data (also when decompressing: a band decodes whole blocks).
  const uint32_t rowUnit = bc ? 4 : 1;
  const TextureFormat outFormat = up.decompressed ? TextureFormat::Rgba8 : c.format;
  auto rowBytes = [&](uint32_t mip, TextureFormat f) {  // bytes of one row unit of level `mip` in format f
    const uint32_t side = c.mipSize(mip);
    return textureImageBytes(f, side, std::min(side, rowUnit));
  };
  // At least one row unit of the largest level must fit (a 16384-wide BC level decompressed: 4 rows, 256 KiB).
  const VkDeviceSize staging =
      std::max({options.stagingBytes, VkDeviceSize{64} << 10, VkDeviceSize(rowBytes(0, outFormat))});
  // Cut every (mip, layer) image into bands that fit the staging buffer.
  std::vector<Piece> pieces;
  for (uint32_t m = 0; m < c.mipCount; ++m) {
    const uint32_t side = c.mipSize(m);
    const uint32_t units = (side + rowUnit - 1) / rowUnit;
    const uint32_t perBand = uint32_t(std::max<VkDeviceSize>(1, staging / rowBytes(m, outFormat)));
    for (uint32_t l = 0; l < c.layers; ++l) {
      for (uint32_t u = 0; u < units; u += perBand) {
        const uint32_t row = u * rowUnit;
        pieces.push_back({m, l, row, std::min(side, (u + std::min(perBand, units - u)) * rowUnit) - row});
      }
    }
  }
  up.gpuBytes = 0;
  for (uint32_t m = 0; m < c.mipCount; ++m)
    up.gpuBytes += textureImageBytes(outFormat, c.mipSize(m), c.mipSize(m)) * c.layers;

  uint64_t classBytes = 0;
  for (const Piece& p : pieces) classBytes += rowBytes(p.mip, outFormat) * ((p.rows + rowUnit - 1) / rowUnit);
  gpu::Buffer buffer(device, std::max<VkDeviceSize>(std::min<VkDeviceSize>(staging, classBytes), 16),
                     VK_BUFFER_USAGE_TRANSFER_SRC_BIT, gpu::MemoryUse::HostVisible);
  up.stagingBytes = buffer.size();
  auto* mapped = static_cast<uint8_t*>(buffer.mapped());
  size_t next = 0;
  bool first = true;
  while (next < pieces.size()) {
    std::vector<VkBufferImageCopy> regions;
    VkDeviceSize used = 0;
    for (; next < pieces.size(); ++next) {
      const Piece& p = pieces[next];
      const uint32_t side = c.mipSize(p.mip);
      const uint32_t units = (p.rows + rowUnit - 1) / rowUnit;
      const VkDeviceSize bytes = rowBytes(p.mip, outFormat) * units;
      if (used + bytes > buffer.size()) break;
      const uint8_t* src = c.texels.data() + c.offset(p.mip, p.layer) + rowBytes(p.mip, c.format) * (p.row / rowUnit);
      if (up.decompressed) {
        const std::vector<uint8_t> rgba = decodeTextureImage(src, side, p.rows, c.format);
        std::memcpy(mapped + used, rgba.data(), rgba.size());
      } else {
        std::memcpy(mapped + used, src, bytes);
      }
      VkBufferImageCopy r{};
      r.bufferOffset = used;  // a multiple of the texel / block size: every piece is whole row units
      r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, p.mip, p.layer, 1};
      r.imageOffset = {0, int32_t(p.row), 0};
      r.imageExtent = {side, p.rows, 1};  // the level's true size: a 2x2 BC level copies its one block
      regions.push_back(r);
      used += bytes;
    }
    VkCommandBuffer cmd = device.beginOneShot();
    if (first) {
      gpu::imageBarrier(cmd, up.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                        VK_PIPELINE_STAGE_2_NONE, VK_ACCESS_2_NONE, VK_PIPELINE_STAGE_2_COPY_BIT,
                        VK_ACCESS_2_TRANSFER_WRITE_BIT);
      first = false;
    }
    vkCmdCopyBufferToImage(cmd, buffer.handle(), up.image.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                           uint32_t(regions.size()), regions.data());
    if (next == pieces.size()) {
      gpu::imageBarrier(cmd, up.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                        VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_SHADER_READ_BIT);
    }
    device.submitOneShot(cmd);  // waits: the staging buffer is free for the next batch
  }
  return up;
}

gpu::Image uploadTextureClass(gpu::Device& device, const TextureClass& c) {
  return std::move(uploadTextureClass(device, c, {}).image);
}

}  // namespace visbuf
