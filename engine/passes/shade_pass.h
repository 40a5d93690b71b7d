// Shading pass (shaders/shade.comp.glsl): one thread per pixel rebuilds the surface from the IDs.
// Reads: frame, ID target, draws, objects, meshes, vertices, indices, materials. Writes: colour.
#pragma once

#include "gpu/pipeline.h"

namespace visbuf::passes {

struct ShadePass {
  gpu::Pipeline pipeline;
  static ShadePass create(gpu::Device& device, VkPipelineLayout layout);
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, uint32_t width,
              uint32_t height) const;
};

}  // namespace visbuf::passes
