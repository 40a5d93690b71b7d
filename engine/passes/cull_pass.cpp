#include "visbuf/passes/cull_pass.h"

#include "visbuf/shared/types.h"

namespace visbuf::passes {

CullPass CullPass::create(gpu::Device& device, VkPipelineLayout layout, const gpu::Specialization& spec) {
  return CullPass{gpu::createComputePipeline(device, layout, "cull.comp", spec)};
}

void CullPass::record(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, uint32_t objectCount,
                      uint32_t phase) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 2, sets, 0, nullptr);
  gpu::PassConstants pc{phase, 0, 0, 0};  // (drawBase: the visibility pass's; lists come from BINDING_DRAW_LISTS)
  vkCmdPushConstants(cmd, layout, gpu::kPassConstantStages, 0, sizeof(pc), &pc);
  vkCmdDispatch(cmd, (objectCount + CULL_WORKGROUP_SIZE - 1) / CULL_WORKGROUP_SIZE, 1, 1);
}

void CullPass::recordListed(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, const gpu::Buffer& lists,
                            VkDeviceSize headerOffset, uint32_t phase, uint32_t variant) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 2, sets, 0, nullptr);
  gpu::PassConstants pc{phase, 0, 0, variant};
  vkCmdPushConstants(cmd, layout, gpu::kPassConstantStages, 0, sizeof(pc), &pc);
  vkCmdDispatchIndirect(cmd, lists.handle(), headerOffset + sizeof(uint32_t));  // header words 1..3
}

}  // namespace visbuf::passes
