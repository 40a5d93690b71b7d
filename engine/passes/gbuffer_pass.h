// G-buffer baseline raster (shaders/gbuffer.{vert,frag}.glsl): the visibility pass's
// vkCmdDrawIndexedIndirectCount over the cull pass's commands, but every depth-passing fragment evaluates
// its surface and writes GBUFFER_TARGETS attribute targets (formats below) plus the reverse-Z D32 depth.
// Reads: frame, objects, vertices, materials, index buffer, draws + draw count. Writes: the targets, depth.
#pragma once

#include <array>

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/passes/visibility_pass.h"
#include "visbuf/shared/config.h"

namespace visbuf::passes {

// The formats of the attribute targets, chosen once per device: the compact usual ones where the device can
// render to them (snorm16 normal and b10g11r11 emissive are optional colour-attachment formats in Vulkan), else
// the mandatory rg16f / rgba16f. The coat target is rgba16f only for scenes with clearcoat materials.
struct GBufferFormats {
  std::array<VkFormat, GBUFFER_TARGETS> color{};
  uint32_t bytesPerPixel() const;  // sum over the targets (depth not included)
  static GBufferFormats choose(gpu::Device& device, bool clearcoat);
};

struct GBufferInputs {
  std::array<const gpu::Image*, GBUFFER_TARGETS> targets{};
  const gpu::Image* depth = nullptr;
  VkBuffer indexBuffer = VK_NULL_HANDLE;
  VkBuffer draws = VK_NULL_HANDLE;
  VkBuffer drawCount = VK_NULL_HANDLE;
  std::vector<VisibilityList> lists;  // the cull pass's draw lists of this phase (as VisibilityInputs::lists)
  bool clear = true;      // early/only phase clears targets and depth; the late phase loads them
  bool countOverdraw = false;  // the variant that counts raster writes into the overdraw image
};

struct GBufferPass {
  gpu::PassLayout layout;
  GBufferFormats formats;
  // Per draw list (its cull mode; masked lists discard like the visibility raster): plain and overdraw-counting.
  std::array<std::array<gpu::Pipeline, 2>, DRAW_LISTS> pipelines;
  static GBufferPass create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec,
                            uint32_t listMask);
  bool created() const { return bool(layout); }
  // Its set: the overdraw counter image (r32ui, GENERAL).
  void bind(const gpu::Image& overdraw) const;
  void record(VkCommandBuffer cmd, VkDescriptorSet scene, const GBufferInputs& in) const;
};

}  // namespace visbuf::passes
