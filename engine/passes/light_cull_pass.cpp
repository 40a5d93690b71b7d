#include "visbuf/passes/light_cull_pass.h"

#include "visbuf/shared/config.h"

namespace visbuf::passes {

void LightCullPass::create(gpu::Device& device, VkPipelineLayout layout, uint32_t windowed) {
  pipeline_ = gpu::createComputePipeline(device, layout, "light_cull.comp", windowed);
  msaaPipeline_ = gpu::createComputePipeline(device, layout, "light_cull_msaa.comp", windowed);
  readback_ = gpu::Buffer(device, LIGHT_TILE_HEADER * sizeof(uint32_t), VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                          gpu::MemoryUse::HostVisible);
}

void LightCullPass::resize(gpu::Device& device, uint32_t width, uint32_t height) {
  tilesX_ = (width + LIGHT_TILE_SIZE - 1) / LIGHT_TILE_SIZE;
  tilesY_ = (height + LIGHT_TILE_SIZE - 1) / LIGHT_TILE_SIZE;
  const VkDeviceSize uints = LIGHT_TILE_HEADER + VkDeviceSize(tilesX_) * tilesY_ * LIGHT_TILE_STRIDE;
  tiles_ = gpu::Buffer(device, uints * sizeof(uint32_t),
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                           VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                       gpu::MemoryUse::DeviceLocal);
}

void LightCullPass::record(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, bool multisampled) const {
  vkCmdFillBuffer(cmd, tiles_.handle(), 0, LIGHT_TILE_HEADER * sizeof(uint32_t), 0);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, (multisampled ? msaaPipeline_ : pipeline_).handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 2, sets, 0, nullptr);
  vkCmdDispatch(cmd, (tilesX_ + 7) / 8, (tilesY_ + 7) / 8, 1);  // one thread per tile, 8x8 per workgroup
}

void LightCullPass::recordReadback(VkCommandBuffer cmd) const {
  VkBufferCopy c{0, 0, LIGHT_TILE_HEADER * sizeof(uint32_t)};
  vkCmdCopyBuffer(cmd, tiles_.handle(), readback_.handle(), 1, &c);
}

LightCullStats LightCullPass::stats() const {
  const auto* h = static_cast<const uint32_t*>(readback_.mapped());
  return {h[LIGHT_STAT_OVERFLOW_TILES], h[LIGHT_STAT_DROPPED], h[LIGHT_STAT_MAX_PER_TILE], h[LIGHT_STAT_PAIRS]};
}

}  // namespace visbuf::passes
