#include "visbuf/passes/shade_pass.h"

#include "visbuf/gpu/resources.h"
#include "visbuf/shared/config.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

ShadePass ShadePass::create(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec) {
  ShadePass p;
  p.pipeline = gpu::createComputePipeline(device, layout, "shade.comp", spec);
  p.attributesPipeline = gpu::createComputePipeline(device, layout, "shade_attributes.comp", spec);
  p.coveredPipeline = gpu::createComputePipeline(device, layout, "shade_covered.comp", spec);
  p.coveredTilesPipeline = gpu::createComputePipeline(device, layout, "covered_tiles.comp", spec);
  return p;
}

void ShadePass::createMsaa(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec) {
  if (msaaPipeline.handle()) return;
  msaaPipeline = gpu::createComputePipeline(device, layout, "shade_msaa.comp", spec);
  sampleIdsPipeline = gpu::createComputePipeline(device, layout, "msaa_ids.comp", spec);
}

namespace {
void dispatchPixels(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, const gpu::Pipeline& p,
                    uint32_t width, uint32_t height) {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 2, sets, 0, nullptr);
  vkCmdDispatch(cmd, (width + SHADE_TILE_X - 1) / SHADE_TILE_X, (height + SHADE_TILE_Y - 1) / SHADE_TILE_Y, 1);
}
}  // namespace

void ShadePass::record(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, uint32_t width,
                       uint32_t height, Variant variant) const {
  dispatchPixels(cmd, layout, sets,
                 variant == Msaa ? msaaPipeline : variant == Attributes ? attributesPipeline : pipeline, width, height);
}

void ShadePass::recordCovered(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets,
                              const gpu::Buffer& tiles, uint32_t width, uint32_t height) const {
  const uint32_t tileCount = ((width + SHADE_TILE_X - 1) / SHADE_TILE_X) * ((height + SHADE_TILE_Y - 1) / SHADE_TILE_Y);
  // (The previous frame's reads of the list are behind the frame graph's frame boundary.)
  vkCmdFillBuffer(cmd, tiles.handle(), 0, COVERED_TILES_HEADER * sizeof(uint32_t), 0);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, coveredTilesPipeline.handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 2, sets, 0, nullptr);
  gpu::PassConstants pc{};
  vkCmdPushConstants(cmd, layout, gpu::kPassConstantStages, 0, sizeof(pc), &pc);
  vkCmdDispatch(cmd, (tileCount + COVERED_TILES_WORKGROUP - 1) / COVERED_TILES_WORKGROUP, 1, 1);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  pc.variant = 1;  // the indirect dispatch from the count
  vkCmdPushConstants(cmd, layout, gpu::kPassConstantStages, 0, sizeof(pc), &pc);
  vkCmdDispatch(cmd, 1, 1, 1);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, coveredPipeline.handle());
  vkCmdDispatchIndirect(cmd, tiles.handle(), 0);
}

void ShadePass::recordSampleIds(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, uint32_t width,
                                uint32_t height) const {
  dispatchPixels(cmd, layout, sets, sampleIdsPipeline, width, height);
}

}  // namespace visbuf::passes
