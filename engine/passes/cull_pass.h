// Cull pass (shaders/cull.comp.glsl): one thread per object, frustum + LOD, appends draw commands to the
// object's draw list (config.h DRAW_LIST_*). Reads: frame, objects, meshes, draw lists (BINDING_DRAW_LISTS: each
// list's region per phase). Writes: draws (indirect arguments), stats (counters, one draw count per list).
#pragma once

#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::passes {

struct CullPass {
  gpu::Pipeline pipeline;
  static CullPass create(gpu::Device& device, VkPipelineLayout layout, const gpu::Specialization& spec);
  // phase: CULL_PHASE_EARLY/LATE. Occlusion mode also reads the depth pyramid and reads/writes the per-object
  // history.
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, uint32_t objectCount,
              uint32_t phase) const;
  // One thread per object of a list in BINDING_VISIBLE_LIST's buffer, whose header (at byte `headerOffset`) holds
  // the dispatch size: the early phase of occlusion culling over last frame's visible list, and the late phase's
  // refinement dispatch (variant CULL_REFINE) over the objects its first dispatch listed (config.h).
  void recordListed(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, const gpu::Buffer& lists,
                    VkDeviceSize headerOffset, uint32_t phase, uint32_t variant) const;
};

}  // namespace visbuf::passes
