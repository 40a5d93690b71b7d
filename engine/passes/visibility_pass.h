// Visibility pass (shaders/visibility.{vert,frag}.glsl): vkCmdDrawIndexedIndirectCount over the cull
// pass's commands into the ID target (r32ui or rg32ui) and reverse-Z D32 depth (cleared to 0).
// Reads: frame, objects, vertices, index buffer, draws + draw count. Writes: ID target, depth.
#pragma once

#include "gpu/pipeline.h"
#include "gpu/resources.h"

namespace visbuf::passes {

struct VisibilityInputs {
  const gpu::Image* ids = nullptr;
  const gpu::Image* depth = nullptr;
  VkBuffer indexBuffer = VK_NULL_HANDLE;
  VkBuffer draws = VK_NULL_HANDLE;
  VkBuffer drawCount = VK_NULL_HANDLE;
  VkDeviceSize drawCountOffset = 0;
  uint32_t maxDraws = 0;
  uint32_t drawBase = 0;  // first slot of this phase: commands are read from draws at drawBase * 20 bytes
  bool clear = true;      // early/only phase clears IDs and depth; the late phase loads them
  bool countOverdraw = false;  // debug: the variant that counts raster writes into BINDING_OVERDRAW
};

struct VisibilityPass {
  gpu::Pipeline narrow;  // r32ui
  gpu::Pipeline wide;    // rg32ui
  gpu::Pipeline narrowOverdraw, wideOverdraw;  // debug variants counting raster writes per pixel
  static VisibilityPass create(gpu::Device& device, VkPipelineLayout layout, uint32_t windowed);
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, const VisibilityInputs& in) const;
};

// Begins dynamic rendering on colour + depth, cleared (depth to 0, reverse-Z) or loaded; shared by the
// visibility and forward passes.
void beginRendering(VkCommandBuffer cmd, const gpu::Image& color, VkClearColorValue clear, const gpu::Image& depth,
                    bool load = false, const gpu::Image* second = nullptr, VkClearColorValue secondClear = {});

}  // namespace visbuf::passes
