#include "passes/forward_pass.h"

#include "passes/visibility_pass.h"

namespace visbuf::passes {

ForwardPass ForwardPass::create(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec) {
  gpu::GraphicsPipelineDesc d;
  d.windowed = spec.windowed;
  d.textureClasses = spec.textureClasses;
  d.vertexShader = "forward.vert";
  d.fragmentShader = "forward.frag";
  d.colorFormats = {VK_FORMAT_R16G16B16A16_SFLOAT};
  ForwardPass p;
  p.pipeline = gpu::createGraphicsPipeline(device, layout, d);
  d.fragmentShader = "forward_ids.frag";
  d.colorFormats = {VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_R32G32_UINT};
  p.pipelineWithIds = gpu::createGraphicsPipeline(device, layout, d);
  d.fragmentShader = "forward_overdraw.frag";
  d.colorFormats = {VK_FORMAT_R16G16B16A16_SFLOAT};
  p.pipelineOverdraw = gpu::createGraphicsPipeline(device, layout, d);
  return p;
}

void ForwardPass::record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, const gpu::Image& color,
                         VkClearColorValue background, const gpu::Image& depth, VkBuffer indexBuffer,
                         const std::vector<ForwardDraw>& draws, const gpu::Image* ids, bool countOverdraw) const {
  if (countOverdraw) ids = nullptr;  // one diagnostic at a time
  beginRendering(cmd, color, background, depth, false, ids, VkClearColorValue{});
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS,
                    (countOverdraw ? pipelineOverdraw : ids ? pipelineWithIds : pipeline).handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 0, 1, &set, 0, nullptr);
  vkCmdBindIndexBuffer(cmd, indexBuffer, 0, VK_INDEX_TYPE_UINT32);
  for (const ForwardDraw& d : draws) vkCmdDrawIndexed(cmd, d.indexCount, 1, d.firstIndex, d.vertexOffset, d.objectId);
  vkCmdEndRendering(cmd);
}

}  // namespace visbuf::passes
