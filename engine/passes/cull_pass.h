// Cull pass (shaders/cull.comp.glsl): one thread per object, frustum + LOD, appends draw commands.
// Reads: frame, objects, meshes. Writes: draws (indirect arguments), stats (counters, draw count).
#pragma once

#include "gpu/pipeline.h"

namespace visbuf::passes {

struct CullPass {
  gpu::Pipeline pipeline;
  static CullPass create(gpu::Device& device, VkPipelineLayout layout, uint32_t windowed);
  // phase: CULL_PHASE_EARLY/LATE; drawBase: first slot of this phase in the draw buffer.
  // Occlusion mode also reads the depth pyramid and reads/writes the per-object history.
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, uint32_t objectCount, uint32_t phase,
              uint32_t drawBase) const;
};

}  // namespace visbuf::passes
