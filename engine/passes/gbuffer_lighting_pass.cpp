#include "visbuf/passes/gbuffer_lighting_pass.h"

#include <vector>

#include "visbuf/shared/bindings_gbuffer_lighting.h"

namespace visbuf::passes {

GBufferLightingPass GBufferLightingPass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout,
                                                uint32_t windowed, uint32_t materialFeatures) {
  constexpr VkDescriptorType storage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  constexpr VkDescriptorType sampled = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  GBufferLightingPass p;
  p.layout = gpu::PassLayout(device, sceneLayout,
                             {{LIGHTING_BINDING_LIGHTS, storage},
                              {LIGHTING_BINDING_LIGHT_TILES, storage},
                              {GBUFFER_LIGHTING_BINDING_TARGETS, sampled, GBUFFER_TARGETS},
                              {GBUFFER_LIGHTING_BINDING_DEPTH, sampled},
                              {GBUFFER_LIGHTING_BINDING_COLOR, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                              {GBUFFER_LIGHTING_BINDING_ATTRIBUTES, storage}},
                             VK_SHADER_STAGE_COMPUTE_BIT);
  gpu::Specialization spec(windowed);
  spec.materialFeatures = materialFeatures;
  p.pipeline = gpu::createComputePipeline(device, p.layout.pipelineLayout(), "gbuffer_lighting.comp", spec);
  p.attributesPipeline =
      gpu::createComputePipeline(device, p.layout.pipelineLayout(), "gbuffer_lighting_attributes.comp", spec);
  return p;
}

void GBufferLightingPass::bind(const GBufferLightingInputs& in) const {
  const VkImageLayout readOnly = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  std::vector<VkDescriptorImageInfo> targets;
  for (const gpu::Image* t : in.targets) targets.push_back({in.sampler, t->view(), readOnly});
  layout.writer()
      .buffer(LIGHTING_BINDING_LIGHTS, in.lights->handle())
      .buffer(LIGHTING_BINDING_LIGHT_TILES, in.lightTiles->handle())
      .images(GBUFFER_LIGHTING_BINDING_TARGETS, std::move(targets))
      .image(GBUFFER_LIGHTING_BINDING_DEPTH, in.depth->view(), readOnly, in.sampler)
      .image(GBUFFER_LIGHTING_BINDING_COLOR, in.color->view(), VK_IMAGE_LAYOUT_GENERAL)
      .buffer(GBUFFER_LIGHTING_BINDING_ATTRIBUTES, in.attributes->handle())
      .update();
}

void GBufferLightingPass::record(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t width, uint32_t height,
                                 bool writeAttributes) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, (writeAttributes ? attributesPipeline : pipeline).handle());
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  vkCmdDispatch(cmd, (width + SHADE_TILE_X - 1) / SHADE_TILE_X, (height + SHADE_TILE_Y - 1) / SHADE_TILE_Y, 1);
}

}  // namespace visbuf::passes
