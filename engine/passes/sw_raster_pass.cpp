#include "visbuf/passes/sw_raster_pass.h"

#include <algorithm>

#include "visbuf/passes/visibility_pass.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

SwRasterPass SwRasterPass::create(gpu::Device& device, VkPipelineLayout layout, const gpu::Specialization& spec) {
  SwRasterPass p;
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
  buffer = gpu::Buffer(device, 8, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                       gpu::MemoryUse::DeviceLocal);
  sized_ = false;
}

bool SwRasterPass::ensureBuffer(gpu::Device& device, uint32_t width, uint32_t height) {
  if (sized_) return false;
  buffer = gpu::Buffer(device, VkDeviceSize(width) * height * 8,
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                       gpu::MemoryUse::DeviceLocal);
  sized_ = true;
  return true;
}

void SwRasterPass::recordRaster(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, uint32_t phase,
                                const gpu::Buffer& stats) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, raster.handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 2, sets, 0, nullptr);
  gpu::PassConstants pc{phase, 0, 0, 0};
  vkCmdPushConstants(cmd, layout, gpu::kPassConstantStages, 0, sizeof(pc), &pc);
  vkCmdDispatchIndirect(cmd, stats.handle(), (SW_ARGS + phase * SW_ARGS_UINTS + SW_ARGS_DISPATCH) * sizeof(uint32_t));
}

void SwRasterPass::recordMerge(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets,
                               const gpu::Image& ids, const gpu::Image& depth, const gpu::Buffer& stats,
                               uint32_t phase) const {
  beginRendering(cmd, ids, {}, depth, /*load=*/true);
  const bool wide = ids.format() == VK_FORMAT_R32G32_UINT;
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, merge[wide ? 1 : 0].handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 0, 2, sets, 0, nullptr);
  vkCmdDrawIndirect(cmd, stats.handle(), (SW_ARGS + phase * SW_ARGS_UINTS + SW_ARGS_MERGE) * sizeof(uint32_t), 1,
                    sizeof(VkDrawIndirectCommand));
  vkCmdEndRendering(cmd);
}

}  // namespace visbuf::passes
