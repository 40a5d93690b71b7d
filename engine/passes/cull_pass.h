// Cull pass (shaders/cull.comp.glsl): one thread per object, frustum + LOD, appends draw commands to the
// object's draw list (config.h DRAW_LIST_*). Reads: frame, objects, meshes, draw lists (each list's region per
// phase). Writes: draws (indirect arguments), stats (counters, one draw count per list).
#pragma once

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::passes {

struct CullPass {
  gpu::PassLayout layout;
  gpu::Pipeline pipeline;
  static CullPass create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, const gpu::Specialization& spec);
  // Its set: the draws it writes, the per-object history and visible lists (config.h VISIBLE_LIST_HEADER), the
  // draw lists and the depth pyramid (GENERAL, all levels).
  void bind(const gpu::Buffer& draws, const gpu::Buffer& history, const gpu::Buffer& visibleList,
            const gpu::Buffer& drawLists, const gpu::Image& pyramid, VkSampler sampler) const;
  // phase: CULL_PHASE_EARLY/LATE. Occlusion mode also reads the depth pyramid and reads/writes the per-object
  // history.
  void record(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t objectCount, uint32_t phase) const;
  // One thread per object of a list in the visible-list buffer, whose header (at byte `headerOffset`) holds the
  // dispatch size: the early phase of occlusion culling over last frame's visible list, and the late phase's
  // refinement dispatch (variant CULL_REFINE) over the objects its first dispatch listed (config.h).
  void recordListed(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Buffer& lists, VkDeviceSize headerOffset,
                    uint32_t phase, uint32_t variant) const;
};

}  // namespace visbuf::passes
