#include "visbuf/passes/sw_raster_pass.h"

#include <algorithm>

#include "visbuf/passes/visibility_pass.h"
#include "visbuf/shared/bindings_sw_raster.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

SwRasterPass SwRasterPass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout,
                                  const gpu::Specialization& spec) {
  constexpr VkDescriptorType storage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  SwRasterPass p;
  p.layout = gpu::PassLayout(device, sceneLayout,
                             {{SW_RASTER_BINDING_DRAWS, storage},
                              {SW_RASTER_BINDING_DRAW_LISTS, storage},
                              {SW_RASTER_BINDING_VISIBILITY, storage},
                              {SW_RASTER_BINDING_VISIBILITY_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER}},
                             VK_SHADER_STAGE_COMPUTE_BIT | VK_SHADER_STAGE_FRAGMENT_BIT);
  const VkPipelineLayout layout = p.layout.pipelineLayout();
  // lavapipe: no load before each atomic, the back-face queue (sw_raster.comp.glsl SW_CPU)
  p.raster = gpu::createComputePipeline(device, layout, device.isCpu() ? "sw_raster_cpu.comp" : "sw_raster.comp", spec);
  for (int wide = 0; wide < 2; ++wide) {
    gpu::GraphicsPipelineDesc d;
    d.vertexShader = "sw_merge.vert";
    d.fragmentShader = wide ? "sw_merge_wide.frag" : "sw_merge.frag";
    d.colorFormats = {wide ? VK_FORMAT_R32G32_UINT : VK_FORMAT_R32_UINT};
    d.cullMode = VK_CULL_MODE_NONE;
    d.windowed = spec.windowed;
    p.merge[wide] = gpu::createGraphicsPipeline(device, layout, d);
  }
  return p;
}

void SwRasterPass::resetBuffer(gpu::Device& device) {
  texels.reset();  // (before its buffer)
  buffer = gpu::Buffer(device, 8,
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                           VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT,
                       gpu::MemoryUse::DeviceLocal);
  texels = gpu::BufferView(device, buffer, VK_FORMAT_R32G32_UINT, 0, 8);
  sized_ = false;
}

bool SwRasterPass::ensureBuffer(gpu::Device& device, uint32_t width, uint32_t height) {
  if (sized_) return false;
  texels.reset();
  buffer = gpu::Buffer(device, VkDeviceSize(width) * height * 8,
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                           VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT,
                       gpu::MemoryUse::DeviceLocal);
  // (SceneFacts::microRasterFits: width x height texels are within maxTexelBufferElements)
  texels = gpu::BufferView(device, buffer, VK_FORMAT_R32G32_UINT, 0, VK_WHOLE_SIZE);
  sized_ = true;
  return true;
}

void SwRasterPass::bind(const gpu::Buffer& draws, const gpu::Buffer& drawLists) const {
  layout.writer()
      .buffer(SW_RASTER_BINDING_DRAWS, draws.handle())
      .buffer(SW_RASTER_BINDING_DRAW_LISTS, drawLists.handle())
      .buffer(SW_RASTER_BINDING_VISIBILITY, buffer.handle())
      .texels(SW_RASTER_BINDING_VISIBILITY_TEXELS, texels.handle())
      .update();
}

void SwRasterPass::recordRaster(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t phase,
                                const gpu::Buffer& stats) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, raster.handle());
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  layout.push(cmd, {phase, 0, 0, 0});
  vkCmdDispatchIndirect(cmd, stats.handle(), (SW_ARGS + phase * SW_ARGS_UINTS + SW_ARGS_DISPATCH) * sizeof(uint32_t));
}

void SwRasterPass::recordMerge(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Image& ids,
                               const gpu::Image& depth, const gpu::Buffer& stats, uint32_t phase) const {
  beginRendering(cmd, ids, {}, depth, /*load=*/true);
  const bool wide = ids.format() == VK_FORMAT_R32G32_UINT;
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, merge[wide ? 1 : 0].handle());
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, scene);
  vkCmdDrawIndirect(cmd, stats.handle(), (SW_ARGS + phase * SW_ARGS_UINTS + SW_ARGS_MERGE) * sizeof(uint32_t), 1,
                    sizeof(VkDrawIndirectCommand));
  vkCmdEndRendering(cmd);
}

}  // namespace visbuf::passes
