#include "passes/shade_pass.h"

#include "shared/config.h"

namespace visbuf::passes {

ShadePass ShadePass::create(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec) {
  return ShadePass{gpu::createComputePipeline(device, layout, "shade.comp", spec),
                   gpu::createComputePipeline(device, layout, "shade_attributes.comp", spec)};
}

void ShadePass::record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, uint32_t width,
                       uint32_t height, bool writeAttributes) const {
  const gpu::Pipeline& p = writeAttributes ? attributesPipeline : pipeline;
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 1, &set, 0, nullptr);
  vkCmdDispatch(cmd, (width + SHADE_TILE_X - 1) / SHADE_TILE_X, (height + SHADE_TILE_Y - 1) / SHADE_TILE_Y, 1);
}

}  // namespace visbuf::passes
