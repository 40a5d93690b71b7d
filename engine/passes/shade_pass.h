// Shading pass (shaders/shade.comp.glsl): one thread per pixel rebuilds the surface from the IDs.
// Reads: frame, ID target, draws, objects, meshes, vertices, indices, materials. Writes: colour, and in the
// attributes variant also the per-pixel reconstruction record (BINDING_ATTRIBUTES, config.h's layout).
#pragma once

#include "gpu/pipeline.h"

namespace visbuf::passes {

struct ShadePass {
  gpu::Pipeline pipeline;
  gpu::Pipeline attributesPipeline;  // same shading, plus the attribute record (stress suite)
  static ShadePass create(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec);
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, uint32_t width, uint32_t height,
              bool writeAttributes) const;
};

}  // namespace visbuf::passes
