#include "visbuf/passes/classify_pass.h"

#include <algorithm>

#include "visbuf/shared/bindings_classify.h"
#include "visbuf/shared/config.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

namespace {
constexpr VkDeviceSize kHeaderBytes = CLASSIFY_HEADER * sizeof(uint32_t);
}

void ClassifyPass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec,
                          std::vector<Variant> variants) {
  std::vector<gpu::DescriptorBinding> bindings = shadeBindings();
  bindings.push_back({CLASSIFY_BINDING_MATERIAL_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER});
  bindings.push_back({CLASSIFY_BINDING_TILE_LIST, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER});
  layout_ = gpu::PassLayout(device, sceneLayout, std::move(bindings), VK_SHADER_STAGE_COMPUTE_BIT);
  const VkPipelineLayout layout = layout_.pipelineLayout();
  variants_ = std::move(variants);
  if (variants_.empty()) variants_.push_back({});  // (a scene without materials: one unused record)
  count_ = gpu::createComputePipeline(device, layout, "classify_count.comp", spec.windowed);
  scan_ = gpu::createComputePipeline(device, layout, "classify_scan.comp", spec.windowed);
  scatter_ = gpu::createComputePipeline(device, layout, "classify_scatter.comp", spec.windowed);
  for (Variant& v : variants_) {
    v.textured = v.textured && spec.textureClasses > 0;
    if (shade_.count(v)) continue;
    gpu::Specialization s = spec;  // (skinned slots, texel views and the rest as the scene has them)
    if (!v.textured) s.textureClasses = 0;
    s.materialFeatures = v.features;
    shade_.emplace(v, gpu::createComputePipeline(device, layout, "shade_classified.comp", s));
  }
  const VkDeviceSize bytes = kHeaderBytes + variants_.size() * sizeof(gpu::MaterialTiles);
  materialTiles_ = gpu::Buffer(device, bytes,
                               VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                   VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                               gpu::MemoryUse::DeviceLocal);
  readback_ = gpu::Buffer(device, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
}

void ClassifyPass::resize(gpu::Device& device, uint32_t width, uint32_t height) {
  tilesX_ = (width + SHADE_TILE_X - 1) / SHADE_TILE_X;
  tilesY_ = (height + SHADE_TILE_Y - 1) / SHADE_TILE_Y;
  const VkDeviceSize perTile = std::min<VkDeviceSize>(variants_.size(), SHADE_TILE_X * SHADE_TILE_Y);
  tileList_ = gpu::Buffer(device, VkDeviceSize(tilesX_) * tilesY_ * perTile * sizeof(uint32_t),
                          VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, gpu::MemoryUse::DeviceLocal);
}

void ClassifyPass::bind(const ShadeInputs& shading) const {
  gpu::DescriptorWriter w = layout_.writer();
  writeShadeBindings(w, shading);
  w.buffer(CLASSIFY_BINDING_MATERIAL_TILES, materialTiles_.handle()).buffer(CLASSIFY_BINDING_TILE_LIST, tileList_.handle());
  w.update();
}

void ClassifyPass::recordClassify(VkCommandBuffer cmd, VkDescriptorSet scene) const {
  constexpr VkAccessFlags2 kReadWrite = VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;
  // The previous frame's shading read the records this frame clears (its fence has passed; ordering only).
  vkCmdFillBuffer(cmd, materialTiles_.handle(), 0, VK_WHOLE_SIZE, 0);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, kReadWrite);
  layout_.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, count_.handle());
  vkCmdDispatch(cmd, tilesX_, tilesY_, 1);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, kReadWrite);
  layout_.push(cmd, {0, 0, uint32_t(variants_.size()), 0});
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scan_.handle());
  vkCmdDispatch(cmd, 1, 1, 1);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, kReadWrite);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scatter_.handle());
  vkCmdDispatch(cmd, tilesX_, tilesY_, 1);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT |
                         VK_PIPELINE_STAGE_2_TRANSFER_BIT,
                     VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT |
                         VK_ACCESS_2_TRANSFER_READ_BIT);
  VkBufferCopy c{0, 0, materialTiles_.size()};
  vkCmdCopyBuffer(cmd, materialTiles_.handle(), readback_.handle(), 1, &c);
}

void ClassifyPass::recordShade(VkCommandBuffer cmd, VkDescriptorSet scene) const {
  layout_.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  for (const auto& [variant, p] : shade_) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
    for (uint32_t m = 0; m < variants_.size(); ++m) {
      if (variants_[m] != variant) continue;
      layout_.push(cmd, {0, 0, m, 0});
      vkCmdDispatchIndirect(cmd, materialTiles_.handle(), kHeaderBytes + VkDeviceSize(m) * sizeof(gpu::MaterialTiles));
    }
  }
}

ClassifyStats ClassifyPass::stats() const {
  const auto* h = static_cast<const uint32_t*>(readback_.mapped());
  const auto* records = reinterpret_cast<const gpu::MaterialTiles*>(h + CLASSIFY_HEADER);
  ClassifyStats s;
  s.pairs = h[CLASSIFY_STAT_PAIRS];
  s.materialsPresent = h[CLASSIFY_STAT_MATERIALS];
  for (size_t m = 0; m < variants_.size(); ++m) {
    s.tiles.push_back(records[m].tiles);
    s.pixels.push_back(records[m].pixels);
  }
  return s;
}

}  // namespace visbuf::passes
