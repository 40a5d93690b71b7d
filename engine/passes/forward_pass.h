// Forward reference pass (shaders/forward.{vert,frag}.glsl): one vkCmdDrawIndexed per object that the
// CPU kept, hardware attribute interpolation, the same lighting. The accuracy reference and the
// "without visbuf" baseline. Draws are grouped by draw list (config.h DRAW_LIST_*) with the same raster state
// as the visibility pass's lists: masked lists discard below the cutoff, face culling per list.
// Reads: frame, objects, vertices, index buffer, materials. Writes: colour (rgba16f attachment), depth.
#pragma once

#include <array>
#include <vector>

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/shared/config.h"

namespace visbuf::passes {

struct ForwardDraw {
  uint32_t indexCount, firstIndex;
  int32_t vertexOffset;
  uint32_t objectId;
  uint32_t list = 0;  // draw list (DRAW_LIST_*): raster state
};

struct ForwardPass {
  // Per draw list: plain; also writing (object + 1, triangle) to an rg32ui target (diagnostics, tests); debug,
  // counting raster writes per pixel into the overdraw image. Created only for the lists in listMask.
  enum Variant { Plain, WithIds, Overdraw, VariantCount };
  gpu::PassLayout layout;
  std::array<std::array<gpu::Pipeline, VariantCount>, DRAW_LISTS> pipelines;
  // samples > 1: pipelines for multisampled colour + depth (no ID variant is used then: see record).
  static ForwardPass create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec,
                            uint32_t listMask, VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT);
  // Its set: the point lights and their tile lists (any buffers where the scene has none: never read then), the
  // overdraw counter image (r32ui, GENERAL).
  void bind(const gpu::Buffer& lights, const gpu::Buffer& lightTiles, const gpu::Image& overdraw) const;
  // ids: optional rg32ui target (cleared to 0) written with the same IDs the visibility path decodes.
  // draws: in any order; the pipeline is rebound where the list changes (sort by list to bind each once).
  // resolve: MSAA, the single-sample image the multisampled colour is averaged into (hardware resolve).
  void record(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Image& color,
              VkClearColorValue background, const gpu::Image& depth, VkBuffer indexBuffer,
              const std::vector<ForwardDraw>& draws, const gpu::Image* ids = nullptr, bool countOverdraw = false,
              const gpu::Image* resolve = nullptr) const;
};

}  // namespace visbuf::passes
