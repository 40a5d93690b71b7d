#include "visbuf/passes/depth_pyramid_pass.h"

#include <algorithm>
#include <bit>

#include "visbuf/gpu/check.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

uint32_t pyramidLevelCount(uint32_t width, uint32_t height) {
  uint32_t levels = 1;
  while (width > 1 || height > 1) {
    width = (width + 1) / 2;
    height = (height + 1) / 2;
    ++levels;
  }
  return levels;
}

DepthPyramidPass::~DepthPyramidPass() {
  if (!device_) return;
  VkDevice dev = device_->device();
  vkDeviceWaitIdle(dev);
  releaseViews();
  vkDestroyDescriptorPool(dev, pool_, nullptr);
  vkDestroySampler(dev, sampler_, nullptr);
  vkDestroyPipelineLayout(dev, layout_, nullptr);
  vkDestroyDescriptorSetLayout(dev, setLayout_, nullptr);
}

void DepthPyramidPass::releaseViews() {
  for (VkImageView v : levelViews_) vkDestroyImageView(device_->device(), v, nullptr);
  levelViews_.clear();
}

void DepthPyramidPass::create(gpu::Device& device) {
  device_ = &device;
  VkDevice dev = device.device();
  VkDescriptorSetLayoutBinding b[3] = {
      {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, PYRAMID_DISPATCH_LEVELS, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {2, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr}};
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = 3;
  lci.pBindings = b;
  VK_CHECK(vkCreateDescriptorSetLayout(dev, &lci, nullptr, &setLayout_));
  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(gpu::PyramidConstants)};
  VkPipelineLayoutCreateInfo pci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pci.setLayoutCount = 1;
  pci.pSetLayouts = &setLayout_;
  pci.pushConstantRangeCount = 1;
  pci.pPushConstantRanges = &range;
  VK_CHECK(vkCreatePipelineLayout(dev, &pci, nullptr, &layout_));
  // One set per dispatch, plus the multisampled first dispatch's.
  constexpr uint32_t maxSets = MAX_PYRAMID_LEVELS / PYRAMID_REDUCTIONS + 2;
  VkDescriptorPoolSize sizes[3] = {{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, maxSets},
                                   {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, maxSets * PYRAMID_DISPATCH_LEVELS},
                                   {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, maxSets}};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  dpci.maxSets = maxSets;
  dpci.poolSizeCount = 3;
  dpci.pPoolSizes = sizes;
  VK_CHECK(vkCreateDescriptorPool(dev, &dpci, nullptr, &pool_));
  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = sci.minFilter = VK_FILTER_NEAREST;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  sci.maxLod = VK_LOD_CLAMP_NONE;
  VK_CHECK(vkCreateSampler(dev, &sci, nullptr, &sampler_));
  pipeline_ = gpu::createComputePipeline(device, layout_, "depth_pyramid.comp");
  msaaPipeline_ = gpu::createComputePipeline(device, layout_, "depth_pyramid_msaa.comp");
}

std::vector<DepthPyramidPass::Dispatch> pyramidDispatches(uint32_t width, uint32_t height) {
  std::vector<DepthPyramidPass::Dispatch> dispatches;
  const uint32_t levels = pyramidLevelCount(width, height);
  uint32_t source = 0;  // the level the dispatch reads (0: the depth image, which it may copy to level 0)
  do {
    DepthPyramidPass::Dispatch d;
    d.source = source;
    d.width = width;
    d.height = height;
    d.reductions = std::min<uint32_t>(PYRAMID_REDUCTIONS, levels - 1 - source);
    dispatches.push_back(d);
    for (uint32_t k = 0; k < d.reductions; ++k) {
      width = (width + 1) / 2;
      height = (height + 1) / 2;
    }
    source += d.reductions;
  } while (source + 1 < levels);
  return dispatches;
}

void DepthPyramidPass::resize(const gpu::Image& depth, const gpu::Image* multisampledDepth) {
  VkDevice dev = device_->device();
  vkDeviceWaitIdle(dev);
  releaseViews();
  if (msaaSet_) sets_.push_back(msaaSet_);
  msaaSet_ = VK_NULL_HANDLE;
  if (!sets_.empty()) vkFreeDescriptorSets(dev, pool_, uint32_t(sets_.size()), sets_.data());
  sets_.clear();
  width_ = depth.width();
  height_ = depth.height();
  levels_ = pyramidLevelCount(width_, height_);
  dispatches_ = pyramidDispatches(width_, height_);
  const uint32_t pw = std::bit_ceil(width_), ph = std::bit_ceil(height_);
  pyramid_ = gpu::Image(*device_, VK_FORMAT_R32_SFLOAT, pw, ph, VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                            VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                        VK_IMAGE_ASPECT_COLOR_BIT, levels_);
  const uint32_t setCount = uint32_t(dispatches_.size()) + (multisampledDepth ? 1 : 0);
  std::vector<VkDescriptorSetLayout> layouts(setCount, setLayout_);
  std::vector<VkDescriptorSet> sets(setCount);
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = pool_;
  ai.descriptorSetCount = setCount;
  ai.pSetLayouts = layouts.data();
  VK_CHECK(vkAllocateDescriptorSets(dev, &ai, sets.data()));
  sets_.assign(sets.begin(), sets.begin() + ptrdiff_t(dispatches_.size()));
  if (multisampledDepth) msaaSet_ = sets.back();
  for (uint32_t k = 0; k < levels_; ++k) levelViews_.push_back(pyramid_.createLevelView(k));
  // The pyramid lives in GENERAL from here on (written as storage, read with texelFetch); it is
  // zero-filled (depth 0 = infinitely far = occludes nothing) so that a pass reading it before the
  // first build sees a valid, conservative pyramid.
  VkCommandBuffer cmd = device_->beginOneShot();
  gpu::imageBarrier(cmd, pyramid_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                    VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
  VkClearColorValue zero{};
  VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, levels_, 0, 1};
  vkCmdClearColorImage(cmd, pyramid_.handle(), VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
  device_->submitOneShot(cmd);
  for (uint32_t i = 0; i < setCount; ++i) {
    const bool msaa = i == dispatches_.size();  // the extra set: the first dispatch over the multisampled depth
    const Dispatch& d = dispatches_[msaa ? 0 : i];
    VkDescriptorImageInfo src =
        msaa        ? VkDescriptorImageInfo{sampler_, multisampledDepth->view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL}
        : i == 0    ? VkDescriptorImageInfo{sampler_, depth.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL}
                    : VkDescriptorImageInfo{sampler_, levelViews_[d.source], VK_IMAGE_LAYOUT_GENERAL};
    // Slot j: the level d.source + j (slot 0 is written by the copying dispatch only); slots past the last level take
    // the last level's view (never written: the dispatch's reduction count stops before them).
    VkDescriptorImageInfo dst[PYRAMID_DISPATCH_LEVELS];
    for (uint32_t j = 0; j < PYRAMID_DISPATCH_LEVELS; ++j)
      dst[j] = {VK_NULL_HANDLE, levelViews_[std::min(d.source + j, levels_ - 1)], VK_IMAGE_LAYOUT_GENERAL};
    VkWriteDescriptorSet w[2] = {{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}, {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}};
    w[0].dstSet = w[1].dstSet = msaa ? msaaSet_ : sets_[i];
    w[0].dstBinding = 0;
    w[0].descriptorCount = 1;
    w[0].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w[0].pImageInfo = &src;
    w[1].dstBinding = 1;
    w[1].descriptorCount = PYRAMID_DISPATCH_LEVELS;
    w[1].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    w[1].pImageInfo = dst;
    vkUpdateDescriptorSets(dev, 2, w, 0, nullptr);
  }
  if (microRaster_) bindMicroRaster(microRaster_);
}

void DepthPyramidPass::bindMicroRaster(VkBufferView texels) {
  microRaster_ = texels;
  std::vector<VkDescriptorSet> all = sets_;
  if (msaaSet_) all.push_back(msaaSet_);
  std::vector<VkWriteDescriptorSet> writes;
  for (VkDescriptorSet set : all) {
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set;
    w.dstBinding = 2;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    w.pTexelBufferView = &microRaster_;
    writes.push_back(w);
  }
  vkUpdateDescriptorSets(device_->device(), uint32_t(writes.size()), writes.data(), 0, nullptr);
}

void DepthPyramidPass::record(VkCommandBuffer cmd, bool multisampled, bool writeLevel0, bool microRaster) const {
  for (size_t i = 0; i < dispatches_.size(); ++i) {
    const Dispatch& d = dispatches_[i];
    const bool fromMicroRaster = d.source == 0 && microRaster;
    gpu::PyramidConstants pc{d.width,
                             d.height,
                             d.source == 0 && writeLevel0 ? 1u : 0u,
                             d.reductions,
                             fromMicroRaster ? 1u : 0u,
                             {}};
    const bool msaa = multisampled && i == 0;
    if (i <= 1) vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, (msaa ? msaaPipeline_ : pipeline_).handle());
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, msaa ? &msaaSet_ : &sets_[i], 0,
                            nullptr);
    vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(pc), &pc);
    // One thread per 2^PYRAMID_REDUCTIONS square of the source, in PYRAMID_TILE squares of threads.
    const uint32_t tile = PYRAMID_TILE << PYRAMID_REDUCTIONS;
    vkCmdDispatch(cmd, (d.width + tile - 1) / tile, (d.height + tile - 1) / tile, 1);
    // The next dispatch reads this one's last level.
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }
}

}  // namespace visbuf::passes
