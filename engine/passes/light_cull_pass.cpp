#include "visbuf/passes/light_cull_pass.h"

#include "visbuf/shared/bindings_light_cull.h"
#include "visbuf/shared/config.h"

namespace visbuf::passes {

void LightCullPass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, uint32_t windowed) {
  layout_ = gpu::PassLayout(device, sceneLayout,
                            {{LIGHT_CULL_BINDING_LIGHTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                             {LIGHT_CULL_BINDING_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                             {LIGHT_CULL_BINDING_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER}},
                            VK_SHADER_STAGE_COMPUTE_BIT);
  pipeline_ = gpu::createComputePipeline(device, layout_.pipelineLayout(), "light_cull.comp", windowed);
  msaaPipeline_ = gpu::createComputePipeline(device, layout_.pipelineLayout(), "light_cull_msaa.comp", windowed);
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

void LightCullPass::bind(const gpu::Buffer& lights, const gpu::Image& depth, VkSampler sampler) const {
  layout_.writer()
      .buffer(LIGHT_CULL_BINDING_LIGHTS, lights.handle())
      .buffer(LIGHT_CULL_BINDING_TILES, tiles_.handle())
      .image(LIGHT_CULL_BINDING_DEPTH, depth.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, sampler)
      .update();
}

void LightCullPass::record(VkCommandBuffer cmd, VkDescriptorSet scene, bool multisampled) const {
  vkCmdFillBuffer(cmd, tiles_.handle(), 0, LIGHT_TILE_HEADER * sizeof(uint32_t), 0);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, (multisampled ? msaaPipeline_ : pipeline_).handle());
  layout_.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
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
