#include "visbuf/passes/shade_pass.h"

#include "visbuf/shared/config.h"

namespace visbuf::passes {

ShadePass ShadePass::create(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec) {
  ShadePass p;
  p.pipeline = gpu::createComputePipeline(device, layout, "shade.comp", spec);
  p.attributesPipeline = gpu::createComputePipeline(device, layout, "shade_attributes.comp", spec);
  return p;
}

void ShadePass::createMsaa(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec) {
  if (msaaPipeline.handle()) return;
  msaaPipeline = gpu::createComputePipeline(device, layout, "shade_msaa.comp", spec);
  sampleIdsPipeline = gpu::createComputePipeline(device, layout, "msaa_ids.comp", spec);
}

namespace {
void dispatchPixels(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, const gpu::Pipeline& p,
                    uint32_t width, uint32_t height) {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 1, &set, 0, nullptr);
  vkCmdDispatch(cmd, (width + SHADE_TILE_X - 1) / SHADE_TILE_X, (height + SHADE_TILE_Y - 1) / SHADE_TILE_Y, 1);
}
}  // namespace

void ShadePass::record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, uint32_t width,
                       uint32_t height, Variant variant) const {
  dispatchPixels(cmd, layout, set,
                 variant == Msaa ? msaaPipeline : variant == Attributes ? attributesPipeline : pipeline, width, height);
}

void ShadePass::recordSampleIds(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, uint32_t width,
                                uint32_t height) const {
  dispatchPixels(cmd, layout, set, sampleIdsPipeline, width, height);
}

}  // namespace visbuf::passes
