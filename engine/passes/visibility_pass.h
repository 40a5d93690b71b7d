// Visibility pass (shaders/visibility.{vert,frag}.glsl): vkCmdDrawIndexedIndirectCount over the cull
// pass's commands into the ID target (r32ui or rg32ui) and reverse-Z D32 depth (cleared to 0), one indirect
// draw per draw list (config.h DRAW_LIST_*) in one rendering instance: opaque lists with the plain pipeline,
// masked lists with the ALPHA_MASK variant (discard below the cutoff); face culling per list.
// Reads: frame, objects, vertices, materials, index buffer, draws + draw counts. Writes: ID target, depth.
#pragma once

#include <array>
#include <vector>

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/shared/config.h"

namespace visbuf::passes {

// Raster state of a draw list: masked lists discard; FLIPPED lists cull front faces (their objects' front faces
// are clockwise on screen: every pipeline keeps counter-clockwise as its front face, so gl_FrontFacing reads the
// same everywhere); DOUBLE_SIDED lists cull nothing.
bool drawListMasked(uint32_t list);
VkCullModeFlags drawListCullMode(uint32_t list);
// The raster state every pass shares for draw list `list`: the frame specialisation (windows, texture classes,
// skinning) and the list's face culling; shaders, formats and samples are the caller's.
gpu::GraphicsPipelineDesc drawListPipelineDesc(const gpu::Specialization& spec, uint32_t list);

struct VisibilityList {
  uint32_t list = DRAW_LIST_OPAQUE;
  uint32_t drawBase = 0;    // first slot of this list and phase: commands are read from draws at drawBase * 20 bytes
  uint32_t countIndex = 0;  // uint index of its draw count in the drawCount buffer
  uint32_t maxDraws = 0;    // the list's capacity
};

struct VisibilityInputs {
  const gpu::Image* ids = nullptr;
  const gpu::Image* depth = nullptr;
  VkBuffer indexBuffer = VK_NULL_HANDLE;
  VkBuffer draws = VK_NULL_HANDLE;
  VkBuffer drawCount = VK_NULL_HANDLE;
  std::vector<VisibilityList> lists;  // drawn in this order (opaque first: masked fragments then fail depth early)
  bool clear = true;      // early/only phase clears IDs and depth; the late phase loads them
  bool idsCleared = false;  // the IDs were cleared before the pass (ShadePass::recordClearIds): loaded, depth cleared
  bool countOverdraw = false;  // debug: the variant that counts raster writes into the overdraw image
};

struct VisibilityPass {
  // Per draw list: r32ui, rg32ui, and the debug variants counting raster writes per pixel (narrow, wide).
  // Created only for the lists in listMask (bit l: list l has objects in the scene).
  enum Variant { Narrow, Wide, NarrowOverdraw, WideOverdraw, VariantCount };
  gpu::PassLayout layout;
  std::array<std::array<gpu::Pipeline, VariantCount>, DRAW_LISTS> pipelines;
  // samples: rasterisation samples of the targets it will draw into (MSAA: multisampled IDs and depth).
  static VisibilityPass create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec,
                               uint32_t listMask, VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT);
  // Its set: the overdraw counter image (r32ui, GENERAL).
  void bind(const gpu::Image& overdraw) const;
  void record(VkCommandBuffer cmd, VkDescriptorSet scene, const VisibilityInputs& in) const;
};

// Begins dynamic rendering on colour + depth, cleared (depth to 0, reverse-Z) or loaded; shared by the
// visibility and forward passes. resolve: a single-sample image that the (multisampled) colour attachment is
// averaged into at the end of the rendering (hardware MSAA resolve; COLOR_ATTACHMENT_OPTIMAL).
void beginRendering(VkCommandBuffer cmd, const gpu::Image& color, VkClearColorValue clear, const gpu::Image& depth,
                    bool load = false, const gpu::Image* second = nullptr, VkClearColorValue secondClear = {},
                    const gpu::Image* resolve = nullptr, bool loadColor = false);

}  // namespace visbuf::passes
