#include "visbuf/passes/shade_pass.h"

#include "visbuf/gpu/resources.h"
#include "visbuf/shared/bindings_shade.h"
#include "visbuf/shared/config.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

std::vector<gpu::DescriptorBinding> shadeBindings() {
  constexpr VkDescriptorType storage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  return {{LIGHTING_BINDING_LIGHTS, storage},
          {LIGHTING_BINDING_LIGHT_TILES, storage},
          {SHADE_BINDING_DRAWS, storage},
          {SHADE_BINDING_DRAW_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER},
          {SHADE_BINDING_VISIBILITY, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
          {SHADE_BINDING_COLOR, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {SHADE_BINDING_ATTRIBUTES, storage},
          {SHADE_BINDING_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
          {SHADE_BINDING_IDS_STORAGE, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {SHADE_BINDING_SW_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER},
          {SHADE_BINDING_COVERED_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER}};
}

void writeShadeBindings(gpu::DescriptorWriter& w, const ShadeInputs& in) {
  w.buffer(LIGHTING_BINDING_LIGHTS, in.lights->handle())
      .buffer(LIGHTING_BINDING_LIGHT_TILES, in.lightTiles->handle())
      .buffer(SHADE_BINDING_DRAWS, in.draws->handle())
      .texels(SHADE_BINDING_DRAW_TEXELS, in.drawTexels)
      .image(SHADE_BINDING_VISIBILITY, in.ids->view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, in.sampler)
      .image(SHADE_BINDING_COLOR, in.color->view(), VK_IMAGE_LAYOUT_GENERAL)
      .buffer(SHADE_BINDING_ATTRIBUTES, in.attributes->handle())
      .image(SHADE_BINDING_DEPTH, in.depth->view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, in.sampler)
      .image(SHADE_BINDING_IDS_STORAGE, in.singleIds->view(), VK_IMAGE_LAYOUT_GENERAL)
      .texels(SHADE_BINDING_SW_TEXELS, in.swTexels)
      .texels(SHADE_BINDING_COVERED_TEXELS, in.coveredTexels);
}

ShadePass ShadePass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec) {
  ShadePass p;
  p.layout = gpu::PassLayout(device, sceneLayout, shadeBindings(), VK_SHADER_STAGE_COMPUTE_BIT);
  const VkPipelineLayout layout = p.layout.pipelineLayout();
  p.pipeline = gpu::createComputePipeline(device, layout, "shade.comp", spec);
  p.attributesPipeline = gpu::createComputePipeline(device, layout, "shade_attributes.comp", spec);
  p.coveredPipeline = gpu::createComputePipeline(device, layout, "shade_covered.comp", spec);
  p.coveredPixelsPipeline = gpu::createComputePipeline(device, layout, "covered_pixels.comp", spec);
  p.clearIdsPipeline[0] = gpu::createComputePipeline(device, layout, "clear_ids.comp");
  p.clearIdsPipeline[1] = gpu::createComputePipeline(device, layout, "clear_ids_wide.comp");
  return p;
}

void ShadePass::createMsaa(gpu::Device& device, gpu::Specialization spec) {
  if (msaaPipeline.handle()) return;
  msaaPipeline = gpu::createComputePipeline(device, layout.pipelineLayout(), "shade_msaa.comp", spec);
  sampleIdsPipeline = gpu::createComputePipeline(device, layout.pipelineLayout(), "msaa_ids.comp", spec);
}

void ShadePass::createResolve(gpu::Device& device, gpu::Specialization spec) {
  if (resolvePipeline.handle()) return;
  const VkPipelineLayout l = layout.pipelineLayout();
  resolvePipeline = gpu::createComputePipeline(device, l, "shade_resolve.comp", spec);
  resolveAttributesPipeline = gpu::createComputePipeline(device, l, "shade_attributes_resolve.comp", spec);
  resolveCoveredPipeline = gpu::createComputePipeline(device, l, "shade_covered_resolve.comp", spec);
  resolveCoveredPixelsPipeline = gpu::createComputePipeline(device, l, "covered_pixels_resolve.comp", spec);
}

void ShadePass::bind(const ShadeInputs& in) const {
  gpu::DescriptorWriter w = layout.writer();
  writeShadeBindings(w, in);
  w.update();
}

void ShadePass::dispatchPixels(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Pipeline& p, uint32_t width,
                               uint32_t height) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  vkCmdDispatch(cmd, (width + SHADE_TILE_X - 1) / SHADE_TILE_X, (height + SHADE_TILE_Y - 1) / SHADE_TILE_Y, 1);
}

void ShadePass::record(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t width, uint32_t height,
                       Variant variant, bool resolved) const {
  const gpu::Pipeline& p = variant == Msaa         ? msaaPipeline
                           : variant == Attributes ? (resolved ? resolveAttributesPipeline : attributesPipeline)
                                                   : (resolved ? resolvePipeline : pipeline);
  dispatchPixels(cmd, scene, p, width, height);
}

void ShadePass::recordCovered(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Buffer& pixels, uint32_t width,
                              uint32_t height, bool resolved) const {
  const uint32_t tileCount = ((width + SHADE_TILE_X - 1) / SHADE_TILE_X) * ((height + SHADE_TILE_Y - 1) / SHADE_TILE_Y);
  // (The previous frame's reads of the list are behind the frame graph's frame boundary.)
  vkCmdFillBuffer(cmd, pixels.handle(), 0, COVERED_PIXELS_HEADER * sizeof(uint32_t), 0);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE,
                    (resolved ? resolveCoveredPixelsPipeline : coveredPixelsPipeline).handle());
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  gpu::PassConstants pc{};
  layout.push(cmd, pc);
  vkCmdDispatch(cmd, (tileCount + COVERED_TILES_WORKGROUP - 1) / COVERED_TILES_WORKGROUP, 1, 1);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  pc.variant = 1;  // the indirect dispatch from the count
  layout.push(cmd, pc);
  vkCmdDispatch(cmd, 1, 1, 1);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, (resolved ? resolveCoveredPipeline : coveredPipeline).handle());
  vkCmdDispatchIndirect(cmd, pixels.handle(), 0);
}

void ShadePass::recordClearIds(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t width, uint32_t height,
                               bool wide) const {
  dispatchPixels(cmd, scene, clearIdsPipeline[wide ? 1 : 0], width, height);
}

void ShadePass::recordSampleIds(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t width, uint32_t height) const {
  dispatchPixels(cmd, scene, sampleIdsPipeline, width, height);
}

}  // namespace visbuf::passes
