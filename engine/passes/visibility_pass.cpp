#include "passes/visibility_pass.h"

#include "shared/types.h"

namespace visbuf::passes {

VisibilityPass VisibilityPass::create(gpu::Device& device, VkPipelineLayout layout, uint32_t windowed) {
  VisibilityPass p;
  gpu::GraphicsPipelineDesc d;
  d.windowed = windowed;
  d.vertexShader = "visibility.vert";
  d.fragmentShader = "visibility.frag";
  d.colorFormats = {VK_FORMAT_R32_UINT};
  p.narrow = gpu::createGraphicsPipeline(device, layout, d);
  d.fragmentShader = "visibility_wide.frag";
  d.colorFormats = {VK_FORMAT_R32G32_UINT};
  p.wide = gpu::createGraphicsPipeline(device, layout, d);
  d.fragmentShader = "visibility_wide_overdraw.frag";
  p.wideOverdraw = gpu::createGraphicsPipeline(device, layout, d);
  d.fragmentShader = "visibility_overdraw.frag";
  d.colorFormats = {VK_FORMAT_R32_UINT};
  p.narrowOverdraw = gpu::createGraphicsPipeline(device, layout, d);
  return p;
}

void beginRendering(VkCommandBuffer cmd, const gpu::Image& color, VkClearColorValue clear, const gpu::Image& depth,
                    bool load, const gpu::Image* second, VkClearColorValue secondClear) {
  VkRenderingAttachmentInfo cas[2] = {{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO},
                                      {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO}};
  for (int i = 0; i < 2; ++i) {
    cas[i].imageView = i == 0 ? color.view() : second ? second->view() : VK_NULL_HANDLE;
    cas[i].imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    cas[i].loadOp = load ? VK_ATTACHMENT_LOAD_OP_LOAD : VK_ATTACHMENT_LOAD_OP_CLEAR;
    cas[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    cas[i].clearValue.color = i == 0 ? clear : secondClear;
  }
  VkRenderingAttachmentInfo da{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  da.imageView = depth.view();
  da.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
  da.loadOp = load ? VK_ATTACHMENT_LOAD_OP_LOAD : VK_ATTACHMENT_LOAD_OP_CLEAR;
  da.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  da.clearValue.depthStencil = {0.0f, 0};  // reverse-Z: 0 is infinitely far
  VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
  ri.renderArea = {{0, 0}, {color.width(), color.height()}};
  ri.layerCount = 1;
  ri.colorAttachmentCount = second ? 2 : 1;
  ri.pColorAttachments = cas;
  ri.pDepthAttachment = &da;
  vkCmdBeginRendering(cmd, &ri);
  VkViewport vp{0.0f, 0.0f, float(color.width()), float(color.height()), 0.0f, 1.0f};
  VkRect2D sc{{0, 0}, {color.width(), color.height()}};
  vkCmdSetViewport(cmd, 0, 1, &vp);
  vkCmdSetScissor(cmd, 0, 1, &sc);
}

void VisibilityPass::record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set,
                            const VisibilityInputs& in) const {
  VkClearColorValue nothing{};
  nothing.uint32[0] = VIS_NOTHING;
  nothing.uint32[1] = VIS_NOTHING;
  beginRendering(cmd, *in.ids, nothing, *in.depth, !in.clear);
  const bool isWide = in.ids->format() == VK_FORMAT_R32G32_UINT;
  const gpu::Pipeline& pipeline = in.countOverdraw ? (isWide ? wideOverdraw : narrowOverdraw) : (isWide ? wide : narrow);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline.handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 0, 1, &set, 0, nullptr);
  vkCmdBindIndexBuffer(cmd, in.indexBuffer, 0, VK_INDEX_TYPE_UINT32);
  gpu::PassConstants pc{0, in.drawBase, 0, 0};
  vkCmdPushConstants(cmd, layout, gpu::kPassConstantStages, 0, sizeof(pc), &pc);
  if (in.maxDraws > 0)
    vkCmdDrawIndexedIndirectCount(cmd, in.draws, VkDeviceSize(in.drawBase) * sizeof(gpu::DrawCommand), in.drawCount,
                                  in.drawCountOffset, in.maxDraws, sizeof(gpu::DrawCommand));
  vkCmdEndRendering(cmd);
}

}  // namespace visbuf::passes
