#include "visbuf/passes/transparent_pass.h"

#include <algorithm>

#include "visbuf/passes/visibility_pass.h"
#include "visbuf/shared/bindings_lighting.h"

namespace visbuf::passes {

void sortBackToFront(std::vector<TransparentDraw>& draws) {
  std::stable_sort(draws.begin(), draws.end(),
                   [](const TransparentDraw& a, const TransparentDraw& b) { return a.viewDepth > b.viewDepth; });
}

TransparentPass TransparentPass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout,
                                        gpu::Specialization spec) {
  TransparentPass p;
  p.layout_ = gpu::PassLayout(device, sceneLayout,
                              {{LIGHTING_BINDING_LIGHTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                               {LIGHTING_BINDING_LIGHT_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}},
                              VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT);
  for (uint32_t list = 0; list < p.pipelines_.size(); ++list) {
    gpu::GraphicsPipelineDesc d = drawListPipelineDesc(spec, list);
    d.vertexShader = "forward.vert";
    d.fragmentShader = "transparent.frag";
    d.colorFormats = {VK_FORMAT_R16G16B16A16_SFLOAT};
    d.depthWrite = false;
    d.premultipliedBlend = true;
    p.pipelines_[list] = gpu::createGraphicsPipeline(device, p.layout_.pipelineLayout(), d);
  }
  return p;
}

void TransparentPass::bind(const gpu::Buffer& lights, const gpu::Buffer& lightTiles) const {
  layout_.writer()
      .buffer(LIGHTING_BINDING_LIGHTS, lights.handle())
      .buffer(LIGHTING_BINDING_LIGHT_TILES, lightTiles.handle())
      .update();
}

void TransparentPass::record(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Image& color, const gpu::Image& depth, VkBuffer indexBuffer,
                             const std::vector<TransparentDraw>& draws) const {
  beginRendering(cmd, color, VkClearColorValue{}, depth, true);
  layout_.bind(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, scene);
  vkCmdBindIndexBuffer(cmd, indexBuffer, 0, VK_INDEX_TYPE_UINT32);
  uint32_t bound = DRAW_LIST_NONE;
  for (const TransparentDraw& t : draws) {
    const ForwardDraw& d = t.draw;
    if (d.list != bound) {
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines_[d.list].handle());
      bound = d.list;
    }
    vkCmdDrawIndexed(cmd, d.indexCount, 1, d.firstIndex, d.vertexOffset, d.objectId);
  }
  vkCmdEndRendering(cmd);
}

}  // namespace visbuf::passes
