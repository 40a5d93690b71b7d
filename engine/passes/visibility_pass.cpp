#include "visbuf/passes/visibility_pass.h"

#include <string>

#include "visbuf/shared/bindings_visibility.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

bool drawListMasked(uint32_t list) { return list >= DRAW_LIST_MASKED && list < DRAW_LISTS; }

VkCullModeFlags drawListCullMode(uint32_t list) {
  switch (list) {
    case DRAW_LIST_OPAQUE_FLIPPED:
    case DRAW_LIST_MASKED_FLIPPED: return VK_CULL_MODE_FRONT_BIT;
    case DRAW_LIST_OPAQUE_DOUBLE_SIDED:
    case DRAW_LIST_MASKED_DOUBLE_SIDED: return VK_CULL_MODE_NONE;
    default: return VK_CULL_MODE_BACK_BIT;
  }
}

gpu::GraphicsPipelineDesc drawListPipelineDesc(const gpu::Specialization& spec, uint32_t list) {
  gpu::GraphicsPipelineDesc d;
  d.windowed = spec.windowed;
  d.textureClasses = spec.textureClasses;
  d.skinned = spec.skinned;
  d.texels = spec.texels;
  d.extras = spec.extras;
  d.pointLights = spec.pointLights;
  d.materialFeatures = spec.materialFeatures;
  d.cullMode = drawListCullMode(list);
  return d;
}

VisibilityPass VisibilityPass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec,
                                      uint32_t listMask, VkSampleCountFlagBits samples) {
  VisibilityPass p;
  p.layout = gpu::PassLayout(device, sceneLayout, {{VISIBILITY_BINDING_OVERDRAW, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}},
                             VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT);
  for (uint32_t list = 0; list < DRAW_LISTS; ++list) {
    if (!(listMask >> list & 1u)) continue;
    const bool masked = drawListMasked(list);
    const std::string prefix = masked ? "visibility_masked" : "visibility";
    gpu::GraphicsPipelineDesc d = drawListPipelineDesc(spec, list);
    d.samples = samples;
    d.vertexShader = prefix + ".vert";
    const char* suffix[VariantCount] = {".frag", "_wide.frag", "_overdraw.frag", "_wide_overdraw.frag"};
    for (int v = 0; v < VariantCount; ++v) {
      d.fragmentShader = prefix + suffix[v];
      d.colorFormats = {v == Wide || v == WideOverdraw ? VK_FORMAT_R32G32_UINT : VK_FORMAT_R32_UINT};
      p.pipelines[list][size_t(v)] = gpu::createGraphicsPipeline(device, p.layout.pipelineLayout(), d);
    }
  }
  return p;
}

void beginRendering(VkCommandBuffer cmd, const gpu::Image& color, VkClearColorValue clear, const gpu::Image& depth,
                    bool load, const gpu::Image* second, VkClearColorValue secondClear, const gpu::Image* resolve,
                    bool loadColor) {
  VkRenderingAttachmentInfo cas[2] = {{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO},
                                      {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO}};
  for (int i = 0; i < 2; ++i) {
    cas[i].imageView = i == 0 ? color.view() : second ? second->view() : VK_NULL_HANDLE;
    cas[i].imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    cas[i].loadOp = load || loadColor ? VK_ATTACHMENT_LOAD_OP_LOAD : VK_ATTACHMENT_LOAD_OP_CLEAR;
    cas[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    cas[i].clearValue.color = i == 0 ? clear : secondClear;
  }
  if (resolve) {
    cas[0].resolveMode = VK_RESOLVE_MODE_AVERAGE_BIT;
    cas[0].resolveImageView = resolve->view();
    cas[0].resolveImageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
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

void VisibilityPass::bind(const gpu::Image& overdraw) const {
  layout.writer().image(VISIBILITY_BINDING_OVERDRAW, overdraw.view(), VK_IMAGE_LAYOUT_GENERAL).update();
}

void VisibilityPass::record(VkCommandBuffer cmd, VkDescriptorSet scene, const VisibilityInputs& in) const {
  VkClearColorValue nothing{};
  nothing.uint32[0] = VIS_NOTHING;
  nothing.uint32[1] = VIS_NOTHING;
  beginRendering(cmd, *in.ids, nothing, *in.depth, !in.clear, nullptr, {}, nullptr, in.idsCleared);
  const bool isWide = in.ids->format() == VK_FORMAT_R32G32_UINT;
  const Variant variant = in.countOverdraw ? (isWide ? WideOverdraw : NarrowOverdraw) : (isWide ? Wide : Narrow);
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, scene);
  vkCmdBindIndexBuffer(cmd, in.indexBuffer, 0, VK_INDEX_TYPE_UINT32);
  for (const VisibilityList& l : in.lists) {
    if (l.maxDraws == 0) continue;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines[l.list][variant].handle());
    layout.push(cmd, {0, l.drawBase, 0, 0});
    vkCmdDrawIndexedIndirectCount(cmd, in.draws, VkDeviceSize(l.drawBase) * sizeof(gpu::DrawCommand), in.drawCount,
                                  VkDeviceSize(l.countIndex) * sizeof(uint32_t), l.maxDraws, sizeof(gpu::DrawCommand));
  }
  vkCmdEndRendering(cmd);
}

}  // namespace visbuf::passes
