// Baked texture classes (scene/texture.h) to GPU images: one sampled 2D array per class, every mip level.
#include <cstring>

#include "visbuf/gpu/check.h"
#include "visbuf/scene/gpu_scene.h"

namespace visbuf {

gpu::Image uploadTextureClass(gpu::Device& device, const TextureClass& c) {
  const VkFormat format = c.colorSpace == ColorSpace::Srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM;
  gpu::Image image(device, format, c.size, c.size, VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                   VK_IMAGE_ASPECT_COLOR_BIT, c.mipCount, c.layers);
  gpu::Buffer staging(device, std::max<VkDeviceSize>(c.texels.size(), 16), VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                      gpu::MemoryUse::HostVisible);
  std::memcpy(staging.mapped(), c.texels.data(), c.texels.size());
  // texels is mip-major: one copy region per level covers every layer of it.
  std::vector<VkBufferImageCopy> regions;
  for (uint32_t m = 0; m < c.mipCount; ++m) {
    const uint32_t size = std::max(c.size >> m, 1u);
    VkBufferImageCopy r{};
    r.bufferOffset = c.offset(m, 0);
    r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, m, 0, c.layers};
    r.imageExtent = {size, size, 1};
    regions.push_back(r);
  }
  VkCommandBuffer cmd = device.beginOneShot();
  gpu::imageBarrier(cmd, image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                    VK_PIPELINE_STAGE_2_NONE, VK_ACCESS_2_NONE, VK_PIPELINE_STAGE_2_COPY_BIT,
                    VK_ACCESS_2_TRANSFER_WRITE_BIT);
  vkCmdCopyBufferToImage(cmd, staging.handle(), image.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                         uint32_t(regions.size()), regions.data());
  gpu::imageBarrier(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                    VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_SHADER_READ_BIT);
  device.submitOneShot(cmd);
  return image;
}

}  // namespace visbuf
