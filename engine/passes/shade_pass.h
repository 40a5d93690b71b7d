// Shading pass (shaders/shade.comp.glsl): one thread per pixel rebuilds the surface from the IDs.
// Reads: frame, ID target, draws, objects, meshes, vertices, indices, materials. Writes: colour, and in the
// attributes variant also the per-pixel reconstruction record (the attribute buffer, config.h's layout).
#pragma once

#include <vector>

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::passes {

// What the shading set holds (shaders/shared/bindings_shade.h): also the classified shading's (classify_pass).
struct ShadeInputs {
  const gpu::Buffer* lights = nullptr;      // point lights (any buffer where the scene has none: never read then)
  const gpu::Buffer* lightTiles = nullptr;  // their tile lists (likewise)
  const gpu::Buffer* draws = nullptr;       // the cull pass's draws
  VkBufferView drawTexels = VK_NULL_HANDLE; // the same as R32UI texels
  const gpu::Image* ids = nullptr;          // the ID target (the multisampled one in MSAA frames), shader-read layout
  VkSampler sampler = VK_NULL_HANDLE;       // for the IDs (nearest)
  const gpu::Image* color = nullptr;        // rgba16f, GENERAL
  const gpu::Buffer* attributes = nullptr;  // the attribute record / sample-ID copy
  const gpu::Image* singleIds = nullptr;    // the single-sampled ID target, GENERAL (clear_ids.comp stores into it)
  const gpu::Image* depth = nullptr;        // the single-sampled depth, shader-read layout (read where the frame
                                            // resolves the micro-raster instead of merging it: FrameData.swResolve)
  VkBufferView swTexels = VK_NULL_HANDLE;   // the micro-raster's buffer as RG32UI texels (read likewise)
  VkBufferView coveredTexels = VK_NULL_HANDLE;  // the covered-pixel list as R32UI texels
};
std::vector<gpu::DescriptorBinding> shadeBindings();
void writeShadeBindings(gpu::DescriptorWriter& w, const ShadeInputs& in);

// MSAA (multisampled ID target bound): the msaa variant shades each pixel once where its samples agree and once per
// distinct ID where they differ (shaders/msaa_samples.glsl), counting those pixels in
// stats[STAT_PER_SAMPLE_PIXELS]; sampleIds copies every sample's raw ID into the attribute buffer (readIds).
struct ShadePass {
  enum Variant { Plain, Attributes, Msaa };
  gpu::PassLayout layout;
  gpu::Pipeline pipeline;
  gpu::Pipeline attributesPipeline;  // same shading, plus the attribute record (stress suite)
  gpu::Pipeline msaaPipeline;        // created by createMsaa (the first MSAA frame): it compiles the materials again
  gpu::Pipeline sampleIdsPipeline;
  gpu::Pipeline coveredPipeline;        // one thread per listed pixel (shade.comp COVERED)
  gpu::Pipeline coveredPixelsPipeline;  // covered_pixels.comp: the list and its indirect dispatch
  // The same four for frames whose micro-raster was not merged (SW_RESOLVE: they read its buffer and the depth),
  // created by createResolve (the first frame that may resolve).
  gpu::Pipeline resolvePipeline, resolveAttributesPipeline, resolveCoveredPipeline, resolveCoveredPixelsPipeline;
  gpu::Pipeline clearIdsPipeline[2];  // clear_ids.comp: r32ui, rg32ui
  static ShadePass create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec);
  void createMsaa(gpu::Device& device, gpu::Specialization spec);
  void createResolve(gpu::Device& device, gpu::Specialization spec);
  void bind(const ShadeInputs& in) const;
  // resolved: the SW_RESOLVE variant (Plain and Attributes; the depth in SHADER_READ_ONLY_OPTIMAL).
  void record(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t width, uint32_t height, Variant variant,
              bool resolved = false) const;
  // The ubershader over the covered pixels only: covered_pixels.comp lists the pixels whose IDs show anything into
  // `pixels` (FrameData.coveredPixels* holds its address) and writes the indirect dispatch, then one thread per
  // listed pixel shades. Reads the IDs (SHADER_READ_ONLY_OPTIMAL); the background was cleared before.
  void recordCovered(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Buffer& pixels, uint32_t width,
                     uint32_t height, bool resolved = false) const;
  // The single-sampled ID target cleared to VIS_NOTHING by a compute store (GENERAL layout): on a GPU the raster's
  // attachment clear of it was slow (clear_ids.comp).
  void recordClearIds(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t width, uint32_t height, bool wide) const;
  void recordSampleIds(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t width, uint32_t height) const;

 private:
  void dispatchPixels(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Pipeline& p, uint32_t width,
                      uint32_t height) const;
};

}  // namespace visbuf::passes
