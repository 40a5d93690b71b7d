// Shading pass (shaders/shade.comp.glsl): one thread per pixel rebuilds the surface from the IDs.
// Reads: frame, ID target, draws, objects, meshes, vertices, indices, materials. Writes: colour, and in the
// attributes variant also the per-pixel reconstruction record (BINDING_ATTRIBUTES, config.h's layout).
#pragma once

#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::passes {

// MSAA (multisampled ID target bound at BINDING_VISIBILITY): the msaa variant shades each pixel once where its
// samples agree and once per distinct ID where they differ (shaders/msaa_samples.glsl), counting those pixels in
// stats[STAT_PER_SAMPLE_PIXELS]; sampleIds copies every sample's raw ID into BINDING_ATTRIBUTES (readIds).
struct ShadePass {
  enum Variant { Plain, Attributes, Msaa };
  gpu::Pipeline pipeline;
  gpu::Pipeline attributesPipeline;  // same shading, plus the attribute record (stress suite)
  gpu::Pipeline msaaPipeline;        // created by createMsaa (the first MSAA frame): it compiles the materials again
  gpu::Pipeline sampleIdsPipeline;
  gpu::Pipeline coveredPipeline;       // one workgroup per listed tile (shade.comp COVERED)
  gpu::Pipeline coveredTilesPipeline;  // covered_tiles.comp: the list and its indirect dispatch
  static ShadePass create(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec);
  void createMsaa(gpu::Device& device, VkPipelineLayout layout, gpu::Specialization spec);
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, uint32_t width, uint32_t height,
              Variant variant) const;
  // The ubershader over the covered tiles only: covered_tiles.comp lists the 8x8 tiles whose IDs show anything
  // into `tiles` (FrameData.coveredTiles* holds its address) and writes the indirect dispatch, then one workgroup
  // per listed tile shades. Reads the IDs (SHADER_READ_ONLY_OPTIMAL); the background was cleared before.
  void recordCovered(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, const gpu::Buffer& tiles,
                     uint32_t width, uint32_t height) const;
  void recordSampleIds(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, uint32_t width,
                       uint32_t height) const;
};

}  // namespace visbuf::passes
