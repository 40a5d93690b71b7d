// Cull pass (shaders/cull.comp.glsl): one thread per object, frustum + LOD, appends draw commands.
// Reads: frame, objects, meshes. Writes: draws (indirect arguments), stats (counters, draw count).
#pragma once

#include "gpu/pipeline.h"

namespace visbuf::passes {

struct CullPass {
  gpu::Pipeline pipeline;
  static CullPass create(gpu::Device& device, VkPipelineLayout layout);
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, uint32_t objectCount) const;
};

}  // namespace visbuf::passes
