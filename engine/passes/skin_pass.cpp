#include "visbuf/passes/skin_pass.h"

#include <array>

#include "visbuf/gpu/check.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

SkinPass::~SkinPass() {
  if (!device_) return;
  VkDevice dev = device_->device();
  vkDestroyDescriptorPool(dev, pool_, nullptr);
  vkDestroyPipelineLayout(dev, layout_, nullptr);
  vkDestroyDescriptorSetLayout(dev, setLayout_, nullptr);
}

void SkinPass::create(gpu::Device& device, const SkinInputs& in, uint32_t vertexWindowShift) {
  device_ = &device;
  vertexWindowShift_ = vertexWindowShift;
  bounds_ = in.bounds;
  gpuBounds_ = in.gpuBounds;
  VkDevice dev = device.device();
  constexpr size_t kBindings = 11;
  const std::array<uint32_t, kBindings> bindings = {
      SKIN_BINDING_VERTICES,   SKIN_BINDING_MESHES,     SKIN_BINDING_SKIN_VERTICES, SKIN_BINDING_JOINTS,
      SKIN_BINDING_INSTANCES,  SKIN_BINDING_VERTICES_1, SKIN_BINDING_VERTICES_2,    SKIN_BINDING_VERTICES_3,
      SKIN_BINDING_EXTRAS,     SKIN_BINDING_BOUNDS,     SKIN_BINDING_MORPH_DELTAS};
  auto whole = [](VkBuffer b) { return VkDescriptorBufferInfo{b, 0, VK_WHOLE_SIZE}; };
  const std::array<VkDescriptorBufferInfo, kBindings> buffers = {
      in.vertexWindows[0],     whole(in.meshes),        whole(in.skinVertices),     whole(in.joints),
      whole(in.instances),     in.vertexWindows[1],     in.vertexWindows[2],        in.vertexWindows[3],
      whole(in.vertexExtras),  whole(in.bounds),        whole(in.morphDeltas)};
  std::array<VkDescriptorSetLayoutBinding, kBindings> b{};
  for (size_t i = 0; i < b.size(); ++i)
    b[i] = {bindings[i], VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = uint32_t(b.size());
  lci.pBindings = b.data();
  VK_CHECK(vkCreateDescriptorSetLayout(dev, &lci, nullptr, &setLayout_));
  VkPushConstantRange range{gpu::kPassConstantStages, 0, sizeof(gpu::PassConstants)};
  VkPipelineLayoutCreateInfo pci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pci.setLayoutCount = 1;
  pci.pSetLayouts = &setLayout_;
  pci.pushConstantRangeCount = 1;
  pci.pPushConstantRanges = &range;
  VK_CHECK(vkCreatePipelineLayout(dev, &pci, nullptr, &layout_));
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, uint32_t(b.size())};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = 1;
  dpci.poolSizeCount = 1;
  dpci.pPoolSizes = &size;
  VK_CHECK(vkCreateDescriptorPool(dev, &dpci, nullptr, &pool_));
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = pool_;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &setLayout_;
  VK_CHECK(vkAllocateDescriptorSets(dev, &ai, &set_));
  std::array<VkDescriptorBufferInfo, kBindings> infos = buffers;
  std::array<VkWriteDescriptorSet, kBindings> writes{};
  for (size_t i = 0; i < writes.size(); ++i) {
    writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    writes[i].dstSet = set_;
    writes[i].dstBinding = bindings[i];
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[i].pBufferInfo = &infos[i];
  }
  vkUpdateDescriptorSets(dev, uint32_t(writes.size()), writes.data(), 0, nullptr);
  pipeline_ = gpu::createComputePipeline(device, layout_, "skin.comp");
  if (gpuBounds_) resolve_ = gpu::createComputePipeline(device, layout_, "skin_bounds.comp");
}

void SkinPass::record(VkCommandBuffer cmd, uint32_t instances, uint32_t maxVertices) const {
  if (instances == 0) return;
  if (gpuBounds_) {  // every record to "empty" (the largest ordered float): the pass only lowers them
    vkCmdFillBuffer(cmd, bounds_, 0, VkDeviceSize(instances) * SKIN_BOUNDS_UINTS * sizeof(uint32_t), 0xffffffffu);
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                       VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  }
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_.handle());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &set_, 0, nullptr);
  gpu::PassConstants pc{instances, vertexWindowShift_, gpuBounds_ ? SKIN_MODE_GPU_BOUNDS : 0u, 0};
  vkCmdPushConstants(cmd, layout_, gpu::kPassConstantStages, 0, sizeof(pc), &pc);
  // Instances along y and z (65,535 each at least), vertices along x.
  const uint32_t y = std::min(instances, 65535u), z = (instances + 65534u) / 65535u;
  const uint32_t vertexGroups = (std::max(maxVertices, 1u) + SKIN_WORKGROUP_SIZE - 1) / SKIN_WORKGROUP_SIZE;
  vkCmdDispatch(cmd, vertexGroups, y, z);
  if (gpuBounds_) {  // AABB -> centre, largest distance from it -> radius (skin.comp.glsl, RESOLVE_BOUNDS)
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, resolve_.handle());
    const uint32_t perInstance = (instances + SKIN_WORKGROUP_SIZE - 1) / SKIN_WORKGROUP_SIZE;
    for (uint32_t step : {SKIN_BOUNDS_CENTRE, SKIN_BOUNDS_DISTANCE, SKIN_BOUNDS_RADIUS}) {
      gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                         VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                         VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
      pc.variant = step;
      vkCmdPushConstants(cmd, layout_, gpu::kPassConstantStages, 0, sizeof(pc), &pc);
      if (step == SKIN_BOUNDS_DISTANCE)
        vkCmdDispatch(cmd, vertexGroups, y, z);
      else
        vkCmdDispatch(cmd, perInstance, 1, 1);
    }
  }
}

}  // namespace visbuf::passes
