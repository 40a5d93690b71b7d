// Descriptor sets from a list of bindings: the set layout, a pool sized from the list and its sets
// (DescriptorLayout), their writes (DescriptorWriter), and a pass's pipeline layout: the scene set at set 0, the
// pass's own set at set 1 and the PassConstants push constants (PassLayout).
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <vector>

#include <vulkan/vulkan.h>

#include "visbuf/gpu/device.h"
#include "visbuf/shared/types.h"

namespace visbuf::gpu {

struct DescriptorBinding {
  uint32_t binding;
  VkDescriptorType type;
  uint32_t count = 1;  // array size
};

// A set layout of `bindings`, each seen by `stages` (only the stages that read them: lavapipe's queue crashed with a
// multisampled image in a binding the graphics stages could see), a pool holding exactly `sets` sets of it, and
// those sets. Move-only; destroys what it created.
class DescriptorLayout {
 public:
  DescriptorLayout() = default;
  DescriptorLayout(Device& device, std::vector<DescriptorBinding> bindings, VkShaderStageFlags stages,
                   uint32_t sets = 1);
  ~DescriptorLayout() { reset(); }
  DescriptorLayout(DescriptorLayout&& o) noexcept { *this = std::move(o); }
  DescriptorLayout& operator=(DescriptorLayout&& o) noexcept;
  DescriptorLayout(const DescriptorLayout&) = delete;
  DescriptorLayout& operator=(const DescriptorLayout&) = delete;

  void reset();
  VkDevice device() const { return device_; }
  VkDescriptorSetLayout layout() const { return layout_; }
  VkDescriptorSet set(uint32_t index = 0) const { return sets_.at(index); }
  // The type of a listed binding (aborts on a binding that is not in the list: a programming error).
  VkDescriptorType type(uint32_t binding) const;

 private:
  // The pool (every binding's count per set, `perType`) and its `sets` sets of the layout.
  void createPool(uint32_t sets, const std::map<VkDescriptorType, uint32_t>& perType);

  VkDevice device_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout layout_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  std::vector<DescriptorBinding> bindings_;
  std::vector<VkDescriptorSet> sets_;
};

// The writes of one set of a DescriptorLayout, by binding (the descriptor type comes from the layout), applied
// together by update().
class DescriptorWriter {
 public:
  explicit DescriptorWriter(const DescriptorLayout& layout, uint32_t set = 0) : layout_(layout), set_(layout.set(set)) {}
  DescriptorWriter& buffer(uint32_t binding, VkBuffer whole) { return buffer(binding, {whole, 0, VK_WHOLE_SIZE}); }
  DescriptorWriter& buffer(uint32_t binding, const VkDescriptorBufferInfo& info);
  DescriptorWriter& image(uint32_t binding, VkImageView view, VkImageLayout layout, VkSampler sampler = VK_NULL_HANDLE) {
    return images(binding, {{sampler, view, layout}});
  }
  DescriptorWriter& images(uint32_t binding, std::vector<VkDescriptorImageInfo> infos);  // an array binding
  DescriptorWriter& texels(uint32_t binding, VkBufferView view);
  void update();

 private:
  VkWriteDescriptorSet& add(uint32_t binding, uint32_t count);
  const DescriptorLayout& layout_;
  VkDescriptorSet set_;
  std::deque<VkDescriptorBufferInfo> buffers_;  // (deques: the writes point into them)
  std::deque<std::vector<VkDescriptorImageInfo>> images_;
  std::deque<VkBufferView> views_;
  std::vector<VkWriteDescriptorSet> writes_;
};

// A pipeline layout of the given set layouts (set i = setLayouts[i]) and the PassConstants range.
VkPipelineLayout createPipelineLayout(Device& device, const std::vector<VkDescriptorSetLayout>& setLayouts);

// A pass's descriptors: its own set (set 1) of `bindings`, and its pipeline layout (the scene set layout at set 0,
// its own at set 1, the PassConstants range). Move-only.
class PassLayout {
 public:
  PassLayout() = default;
  PassLayout(Device& device, VkDescriptorSetLayout sceneLayout, std::vector<DescriptorBinding> bindings,
             VkShaderStageFlags stages);
  ~PassLayout() { reset(); }
  PassLayout(PassLayout&& o) noexcept { *this = std::move(o); }
  PassLayout& operator=(PassLayout&& o) noexcept;
  PassLayout(const PassLayout&) = delete;
  PassLayout& operator=(const PassLayout&) = delete;

  void reset();
  explicit operator bool() const { return pipelineLayout_ != VK_NULL_HANDLE; }
  VkPipelineLayout pipelineLayout() const { return pipelineLayout_; }
  DescriptorWriter writer() const { return DescriptorWriter(set_); }
  // Binds the scene set (set 0) and the pass's own set (set 1).
  void bind(VkCommandBuffer cmd, VkPipelineBindPoint point, VkDescriptorSet scene) const;
  void push(VkCommandBuffer cmd, const PassConstants& constants) const;

 private:
  DescriptorLayout set_;
  VkPipelineLayout pipelineLayout_ = VK_NULL_HANDLE;
};

}  // namespace visbuf::gpu
