#include "visbuf/passes/cull_pass.h"

#include "visbuf/gpu/resources.h"
#include "visbuf/shared/bindings_cull.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

CullPass CullPass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, const gpu::Specialization& spec) {
  constexpr VkDescriptorType storage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  CullPass p{gpu::PassLayout(device, sceneLayout,
                             {{CULL_BINDING_DRAWS, storage},
                              {CULL_BINDING_HISTORY, storage},
                              {CULL_BINDING_VISIBLE_LIST, storage},
                              {CULL_BINDING_DRAW_LISTS, storage},
                              {CULL_BINDING_PYRAMID, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
                              {CULL_BINDING_CLUSTERS, storage}},
                             VK_SHADER_STAGE_COMPUTE_BIT),
             {}};
  p.pipeline = gpu::createComputePipeline(device, p.layout.pipelineLayout(), "cull.comp", spec);
  p.clusterPipeline = gpu::createComputePipeline(device, p.layout.pipelineLayout(), "cull_clusters.comp", spec);
  p.sievePipeline = gpu::createComputePipeline(device, p.layout.pipelineLayout(), "cull_sieve.comp", spec);
  p.occlusionPipeline = gpu::createComputePipeline(device, p.layout.pipelineLayout(), "cull_occlusion.comp", spec);
  p.retestPipeline = gpu::createComputePipeline(device, p.layout.pipelineLayout(), "cull_cluster_retest.comp", spec);
  return p;
}

void CullPass::bind(const gpu::Buffer& draws, const gpu::Buffer& history, const gpu::Buffer& visibleList,
                    const gpu::Buffer& drawLists, const gpu::Image& pyramid, VkSampler sampler,
                    const gpu::Buffer& clusters) const {
  layout.writer()
      .buffer(CULL_BINDING_DRAWS, draws.handle())
      .buffer(CULL_BINDING_HISTORY, history.handle())
      .buffer(CULL_BINDING_VISIBLE_LIST, visibleList.handle())
      .buffer(CULL_BINDING_DRAW_LISTS, drawLists.handle())
      .image(CULL_BINDING_PYRAMID, pyramid.view(), VK_IMAGE_LAYOUT_GENERAL, sampler)
      .buffer(CULL_BINDING_CLUSTERS, clusters.handle())
      .update();
}

void CullPass::record(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t objectCount, uint32_t phase) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  layout.push(cmd, {phase, 0, 0, 0});  // (drawBase: the visibility pass's; lists come from the draw lists' buffer)
  vkCmdDispatch(cmd, (objectCount + CULL_WORKGROUP_SIZE - 1) / CULL_WORKGROUP_SIZE, 1, 1);
}

void CullPass::recordSieve(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t objectCount) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, sievePipeline.handle());
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  layout.push(cmd, {CULL_PHASE_LATE, 0, 0, CULL_LATE_LISTED});
  const uint32_t perWorkgroup = CULL_WORKGROUP_SIZE * SIEVE_OBJECTS_PER_THREAD;
  vkCmdDispatch(cmd, (objectCount + perWorkgroup - 1) / perWorkgroup, 1, 1);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  layout.push(cmd, {CULL_PHASE_LATE, 0, 1, CULL_LATE_LISTED});  // its second step: the late cull's dispatch size
  vkCmdDispatch(cmd, 1, 1, 1);
}

void CullPass::recordOcclusionCount(VkCommandBuffer cmd, VkDescriptorSet scene) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, sievePipeline.handle());
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  layout.push(cmd, {CULL_PHASE_LATE, 0, 2, CULL_LATE_LISTED});  // the sieve's third step (cull_sieve.comp)
  vkCmdDispatch(cmd, 1, 1, 1);
}

void CullPass::recordListed(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Buffer& lists,
                            VkDeviceSize headerOffset, uint32_t phase, uint32_t variant) const {
  const gpu::Pipeline& p = variant == CULL_CLUSTERS                                 ? clusterPipeline
                          : variant == CULL_CLUSTER_RETEST                         ? retestPipeline
                          : variant == CULL_LATE_LISTED || variant == CULL_REFINE ? occlusionPipeline
                                                                                   : pipeline;
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, scene);
  layout.push(cmd, {phase, 0, 0, variant});
  vkCmdDispatchIndirect(cmd, lists.handle(), headerOffset + sizeof(uint32_t));  // header words 1..3
}

}  // namespace visbuf::passes
