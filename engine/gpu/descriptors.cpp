#include "visbuf/gpu/descriptors.h"

#include <cstdio>
#include <cstdlib>
#include <map>
#include <utility>

#include "visbuf/core/log.h"
#include "visbuf/gpu/check.h"
#include "visbuf/gpu/pipeline.h"

namespace visbuf::gpu {

DescriptorLayout::DescriptorLayout(Device& device, std::vector<DescriptorBinding> bindings,
                                   VkShaderStageFlags stages, uint32_t sets)
    : device_(device.device()), bindings_(std::move(bindings)) {
  std::vector<VkDescriptorSetLayoutBinding> b;
  std::map<VkDescriptorType, uint32_t> perType;  // the pool: every binding's count, per set
  for (const DescriptorBinding& x : bindings_) {
    b.push_back({x.binding, x.type, x.count, stages, nullptr});
    perType[x.type] += x.count * sets;
  }
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = uint32_t(b.size());
  lci.pBindings = b.data();
  VK_CHECK(vkCreateDescriptorSetLayout(device_, &lci, nullptr, &layout_));
  try {  // (a failure below releases the layout: no destructor runs for an object whose constructor threw)
    createPool(sets, perType);
  } catch (...) {
    reset();
    throw;
  }
}

void DescriptorLayout::createPool(uint32_t sets, const std::map<VkDescriptorType, uint32_t>& perType) {
  std::vector<VkDescriptorPoolSize> sizes;
  for (auto [type, count] : perType) sizes.push_back({type, count});
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = sets;
  dpci.poolSizeCount = uint32_t(sizes.size());
  dpci.pPoolSizes = sizes.data();
  VK_CHECK(vkCreateDescriptorPool(device_, &dpci, nullptr, &pool_));
  const std::vector<VkDescriptorSetLayout> layouts(sets, layout_);
  sets_.resize(sets);
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = pool_;
  ai.descriptorSetCount = sets;
  ai.pSetLayouts = layouts.data();
  VK_CHECK(vkAllocateDescriptorSets(device_, &ai, sets_.data()));
}

DescriptorLayout& DescriptorLayout::operator=(DescriptorLayout&& o) noexcept {
  if (this != &o) {
    reset();
    device_ = std::exchange(o.device_, VK_NULL_HANDLE);
    layout_ = std::exchange(o.layout_, VK_NULL_HANDLE);
    pool_ = std::exchange(o.pool_, VK_NULL_HANDLE);
    bindings_ = std::move(o.bindings_);
    sets_ = std::move(o.sets_);
  }
  return *this;
}

void DescriptorLayout::reset() {
  if (!device_) return;
  vkDestroyDescriptorPool(device_, pool_, nullptr);  // (frees the sets)
  vkDestroyDescriptorSetLayout(device_, layout_, nullptr);
  device_ = VK_NULL_HANDLE;
  layout_ = VK_NULL_HANDLE;
  pool_ = VK_NULL_HANDLE;
  bindings_.clear();
  sets_.clear();
}

VkDescriptorType DescriptorLayout::type(uint32_t binding) const {
  for (const DescriptorBinding& b : bindings_)
    if (b.binding == binding) return b.type;
  logMessage(LogLevel::Error, "descriptor binding " + std::to_string(binding) + " is not in the set layout");
  std::abort();
}

VkWriteDescriptorSet& DescriptorWriter::add(uint32_t binding, uint32_t count) {
  VkWriteDescriptorSet& w = writes_.emplace_back(VkWriteDescriptorSet{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET});
  w.dstSet = set_;
  w.dstBinding = binding;
  w.descriptorCount = count;
  w.descriptorType = layout_.type(binding);
  return w;
}

DescriptorWriter& DescriptorWriter::buffer(uint32_t binding, const VkDescriptorBufferInfo& info) {
  add(binding, 1).pBufferInfo = &buffers_.emplace_back(info);
  return *this;
}

DescriptorWriter& DescriptorWriter::images(uint32_t binding, std::vector<VkDescriptorImageInfo> infos) {
  const std::vector<VkDescriptorImageInfo>& kept = images_.emplace_back(std::move(infos));
  add(binding, uint32_t(kept.size())).pImageInfo = kept.data();
  return *this;
}

DescriptorWriter& DescriptorWriter::texels(uint32_t binding, VkBufferView view) {
  add(binding, 1).pTexelBufferView = &views_.emplace_back(view);
  return *this;
}

void DescriptorWriter::update() {
  vkUpdateDescriptorSets(layout_.device(), uint32_t(writes_.size()), writes_.data(), 0, nullptr);
  writes_.clear();
}

VkPipelineLayout createPipelineLayout(Device& device, const std::vector<VkDescriptorSetLayout>& setLayouts) {
  VkPushConstantRange range{kPassConstantStages, 0, sizeof(PassConstants)};
  VkPipelineLayoutCreateInfo pci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pci.setLayoutCount = uint32_t(setLayouts.size());
  pci.pSetLayouts = setLayouts.data();
  pci.pushConstantRangeCount = 1;
  pci.pPushConstantRanges = &range;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VK_CHECK(vkCreatePipelineLayout(device.device(), &pci, nullptr, &layout));
  return layout;
}

PassLayout::PassLayout(Device& device, VkDescriptorSetLayout sceneLayout, std::vector<DescriptorBinding> bindings,
                       VkShaderStageFlags stages)
    : set_(device, std::move(bindings), stages),
      pipelineLayout_(createPipelineLayout(device, {sceneLayout, set_.layout()})) {}

PassLayout& PassLayout::operator=(PassLayout&& o) noexcept {
  if (this != &o) {
    reset();
    pipelineLayout_ = std::exchange(o.pipelineLayout_, VK_NULL_HANDLE);
    set_ = std::move(o.set_);
  }
  return *this;
}

void PassLayout::reset() {
  if (pipelineLayout_) vkDestroyPipelineLayout(set_.device(), pipelineLayout_, nullptr);
  pipelineLayout_ = VK_NULL_HANDLE;
  set_.reset();
}

void PassLayout::bind(VkCommandBuffer cmd, VkPipelineBindPoint point, VkDescriptorSet scene) const {
  const VkDescriptorSet sets[2] = {scene, set_.set()};
  vkCmdBindDescriptorSets(cmd, point, pipelineLayout_, 0, 2, sets, 0, nullptr);
}

void PassLayout::push(VkCommandBuffer cmd, const PassConstants& constants) const {
  vkCmdPushConstants(cmd, pipelineLayout_, kPassConstantStages, 0, sizeof(constants), &constants);
}

}  // namespace visbuf::gpu
