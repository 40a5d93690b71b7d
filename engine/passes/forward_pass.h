// Forward reference pass (shaders/forward.{vert,frag}.glsl): one vkCmdDrawIndexed per object that the
// CPU kept, hardware attribute interpolation, the same lighting. The accuracy reference and the
// "without visbuf" baseline. Reads: frame, objects, vertices, index buffer, materials.
// Writes: colour (rgba16f attachment), depth.
#pragma once

#include <vector>

#include "gpu/pipeline.h"
#include "gpu/resources.h"

namespace visbuf::passes {

struct ForwardDraw {
  uint32_t indexCount, firstIndex;
  int32_t vertexOffset;
  uint32_t objectId;
};

struct ForwardPass {
  gpu::Pipeline pipeline;
  gpu::Pipeline pipelineWithIds;  // also writes (object + 1, triangle) to an rg32ui target (diagnostics, tests)
  gpu::Pipeline pipelineOverdraw; // debug: counts raster writes per pixel into BINDING_OVERDRAW
  static ForwardPass create(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec);
  // ids: optional rg32ui target (cleared to 0) written with the same IDs the visibility path decodes.
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, const gpu::Image& color,
              VkClearColorValue background, const gpu::Image& depth, VkBuffer indexBuffer,
              const std::vector<ForwardDraw>& draws, const gpu::Image* ids = nullptr, bool countOverdraw = false) const;
};

}  // namespace visbuf::passes
