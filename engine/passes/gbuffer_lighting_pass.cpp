#include "visbuf/passes/gbuffer_lighting_pass.h"

#include "visbuf/shared/config.h"

namespace visbuf::passes {

GBufferLightingPass GBufferLightingPass::create(gpu::Device& device, VkPipelineLayout layout, uint32_t windowed) {
  return GBufferLightingPass{
      gpu::createComputePipeline(device, layout, "gbuffer_lighting.comp", windowed),
      gpu::createComputePipeline(device, layout, "gbuffer_lighting_attributes.comp", windowed)};
}

void GBufferLightingPass::record(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, uint32_t width,
                                 uint32_t height, bool writeAttributes) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, (writeAttributes ? attributesPipeline : pipeline).handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 2, sets, 0, nullptr);
  vkCmdDispatch(cmd, (width + SHADE_TILE_X - 1) / SHADE_TILE_X, (height + SHADE_TILE_Y - 1) / SHADE_TILE_Y, 1);
}

}  // namespace visbuf::passes
