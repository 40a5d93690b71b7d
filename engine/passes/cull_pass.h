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
  gpu::Pipeline clusterPipeline;  // the cluster dispatch (CULL_CLUSTERS, cull_clusters.comp.glsl)
  gpu::Pipeline sievePipeline;    // the late phase's frustum sieve (CULL_LATE_LISTED, cull_sieve.comp.glsl)
  // The late phase's occlusion test (CULL_LATE_LISTED and CULL_REFINE, cull_occlusion.comp.glsl)
  gpu::Pipeline occlusionPipeline;
  gpu::Pipeline retestPipeline;   // the deferred clusters' retest (CULL_CLUSTER_RETEST, cull_cluster_retest.comp.glsl)
  static CullPass create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, const gpu::Specialization& spec);
  // Its set: the draws it writes, the per-object history and visible lists (config.h VISIBLE_LIST_HEADER, then the
  // cluster lists' entries), the draw lists, the depth pyramid (GENERAL, all levels) and the scene's clusters.
  void bind(const gpu::Buffer& draws, const gpu::Buffer& history, const gpu::Buffer& visibleList,
            const gpu::Buffer& drawLists, const gpu::Image& pyramid, VkSampler sampler,
            const gpu::Buffer& clusters) const;
  // phase: CULL_PHASE_EARLY/LATE. Occlusion mode also reads the depth pyramid and reads/writes the per-object
  // history.
  void record(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t objectCount, uint32_t phase) const;
  // The late phase's frustum sieve over every object: it lists those inside for the late cull (recordListed with
  // variant CULL_LATE_LISTED at the late list, config.h LATE_LIST_WORD); a second one-thread dispatch sizes the late
  // cull's from the list's count.
  void recordSieve(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t objectCount) const;
  // After the late phase's occlusion tests (and their refinement): STAT_OCCLUSION_CULLED from the lists' counts.
  void recordOcclusionCount(VkCommandBuffer cmd, VkDescriptorSet scene) const;
  // An indirect dispatch over a list whose header (at byte `headerOffset` of `lists`) holds the dispatch size: one
  // thread per object of the early phase of occlusion culling over last frame's visible list, of the late phase's
  // occlusion test over the objects inside the frustum (variant CULL_LATE_LISTED), of its refinement dispatch
  // (variant CULL_REFINE) over the objects the first listed, and of the late draw dispatch (variant CULL_LATE_DRAW)
  // over the objects those two listed to draw; one workgroup per object of the cluster dispatch (variant
  // CULL_CLUSTERS, its header in the stats buffer); one thread per deferred cluster of the late phase's retest
  // (variant CULL_CLUSTER_RETEST, its header in the stats buffer) (config.h).
  void recordListed(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Buffer& lists, VkDeviceSize headerOffset,
                    uint32_t phase, uint32_t variant) const;
};

}  // namespace visbuf::passes
