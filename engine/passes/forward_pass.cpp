#include "visbuf/passes/forward_pass.h"

#include <string>

#include "visbuf/passes/visibility_pass.h"
#include "visbuf/shared/bindings_forward.h"

namespace visbuf::passes {

ForwardPass ForwardPass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec,
                                uint32_t listMask, VkSampleCountFlagBits samples) {
  ForwardPass p;
  p.layout = gpu::PassLayout(device, sceneLayout,
                             {{LIGHTING_BINDING_LIGHTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                              {LIGHTING_BINDING_LIGHT_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                              {FORWARD_BINDING_OVERDRAW, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}},
                             VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT);
  const VkPipelineLayout layout = p.layout.pipelineLayout();
  for (uint32_t list = 0; list < DRAW_LISTS; ++list) {
    if (!(listMask >> list & 1u)) continue;
    const std::string prefix = drawListMasked(list) ? "forward_masked" : "forward";
    gpu::GraphicsPipelineDesc d = drawListPipelineDesc(spec, list);
    d.samples = samples;
    d.vertexShader = "forward.vert";
    d.fragmentShader = prefix + ".frag";
    d.colorFormats = {VK_FORMAT_R16G16B16A16_SFLOAT};
    p.pipelines[list][Plain] = gpu::createGraphicsPipeline(device, layout, d);
    d.fragmentShader = prefix + "_ids.frag";
    d.colorFormats = {VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_R32G32_UINT};
    p.pipelines[list][WithIds] = gpu::createGraphicsPipeline(device, layout, d);
    d.fragmentShader = prefix + "_overdraw.frag";
    d.colorFormats = {VK_FORMAT_R16G16B16A16_SFLOAT};
    p.pipelines[list][Overdraw] = gpu::createGraphicsPipeline(device, layout, d);
  }
  return p;
}

void ForwardPass::bind(const gpu::Buffer& lights, const gpu::Buffer& lightTiles, const gpu::Image& overdraw) const {
  layout.writer()
      .buffer(LIGHTING_BINDING_LIGHTS, lights.handle())
      .buffer(LIGHTING_BINDING_LIGHT_TILES, lightTiles.handle())
      .image(FORWARD_BINDING_OVERDRAW, overdraw.view(), VK_IMAGE_LAYOUT_GENERAL)
      .update();
}

void ForwardPass::record(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Image& color,
                         VkClearColorValue background, const gpu::Image& depth, VkBuffer indexBuffer,
                         const std::vector<ForwardDraw>& draws, const gpu::Image* ids, bool countOverdraw,
                         const gpu::Image* resolve) const {
  if (countOverdraw) ids = nullptr;  // one diagnostic at a time
  beginRendering(cmd, color, background, depth, false, ids, VkClearColorValue{}, resolve);
  const Variant variant = countOverdraw ? Overdraw : ids ? WithIds : Plain;
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, scene);
  vkCmdBindIndexBuffer(cmd, indexBuffer, 0, VK_INDEX_TYPE_UINT32);
  uint32_t bound = DRAW_LIST_NONE;
  for (const ForwardDraw& d : draws) {
    if (d.list != bound) {
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines[d.list][variant].handle());
      bound = d.list;
    }
    vkCmdDrawIndexed(cmd, d.indexCount, 1, d.firstIndex, d.vertexOffset, d.objectId);
  }
  vkCmdEndRendering(cmd);
}

}  // namespace visbuf::passes
