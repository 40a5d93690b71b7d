// Depth pyramid pass (shaders/depth_pyramid.comp.glsl): a conservative farthest-depth (reverse-Z
// minimum) reduction of the visibility depth over every level, up to PYRAMID_REDUCTIONS levels per dispatch.
// Reads: depth (SHADER_READ_ONLY_OPTIMAL). Writes: pyramid (r32f, GENERAL, all levels).
// Level 0 is full resolution; level k's valid size is ceil(size / 2^k). The image is allocated with
// power-of-two extents >= the valid sizes so every valid texel exists at every level.
#pragma once

#include <vector>

#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::passes {

// Number of levels until the valid size is 1x1.
uint32_t pyramidLevelCount(uint32_t width, uint32_t height);

class DepthPyramidPass {
 public:
  // One dispatch: it reads level `source` (valid size width x height; 0: the depth image, copied to level 0 on
  // request) and writes the next `reductions` levels.
  struct Dispatch {
    uint32_t source = 0, width = 0, height = 0, reductions = 0;
  };
  DepthPyramidPass() = default;
  ~DepthPyramidPass();
  DepthPyramidPass(const DepthPyramidPass&) = delete;
  DepthPyramidPass& operator=(const DepthPyramidPass&) = delete;
  void create(gpu::Device& device);
  // (Re)creates the pyramid image for a depth image of this size and writes the per-level descriptors.
  // multisampledDepth (MSAA, same size): level 0 can also be built from it, as the farthest depth of each
  // pixel's samples (record with multisampled = true).
  void resize(const gpu::Image& depth, const gpu::Image* multisampledDepth = nullptr);
  // writeLevel0: also copy the depth into level 0 (the occlusion tests never read it: PYRAMID_FIRST_TESTED_LEVEL;
  // only a read-back of every level needs it).
  // microRaster: the micro-raster's buffer (bindMicroRaster) was not merged into the depth: level 0 is then the nearer
  // of the two per pixel; false: the depth alone.
  void record(VkCommandBuffer cmd, bool multisampled = false, bool writeLevel0 = false, bool microRaster = false) const;
  // The micro-raster's buffer as RG32UI texels (passes::SwRasterPass::texels), read where record's microRaster is
  // set; every set takes it (again after resize). A view must be bound before the first record.
  void bindMicroRaster(VkBufferView texels);
  const gpu::Image& pyramid() const { return pyramid_; }
  uint32_t levels() const { return levels_; }

 private:
  void releaseViews();
  gpu::Device* device_ = nullptr;
  VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkSampler sampler_ = VK_NULL_HANDLE;
  gpu::Pipeline pipeline_;
  gpu::Pipeline msaaPipeline_;  // level 0 from a multisampled depth
  VkDescriptorSet msaaSet_ = VK_NULL_HANDLE;
  gpu::Image pyramid_;
  std::vector<VkImageView> levelViews_;
  std::vector<VkDescriptorSet> sets_;  // one per dispatch
  std::vector<Dispatch> dispatches_;
  uint32_t width_ = 0, height_ = 0, levels_ = 0;
  VkBufferView microRaster_ = VK_NULL_HANDLE;
};

// The dispatches that build the pyramid of a depth image of this size: each reduces up to PYRAMID_REDUCTIONS levels
// from where the one before stopped; together they write every level once.
std::vector<DepthPyramidPass::Dispatch> pyramidDispatches(uint32_t width, uint32_t height);

}  // namespace visbuf::passes
