// G-buffer baseline lighting (shaders/gbuffer_lighting.comp.glsl): one thread per pixel reads the attribute
// targets (BINDING_GBUFFER) and the depth (BINDING_GBUFFER_DEPTH), rebuilds the camera-relative position from the
// depth and calls shadeSurface(). Reads: frame, the targets, depth. Writes: colour (rgba16f, GENERAL), covered
// pixels only (the frame script clears it to the background first, as for shade_pass); the attributes variant
// also writes the rebuilt position and depth to BINDING_ATTRIBUTES (slots 0..3 of config.h's record, 7 = 1).
#pragma once

#include "visbuf/gpu/pipeline.h"

namespace visbuf::passes {

struct GBufferLightingPass {
  gpu::Pipeline pipeline;
  gpu::Pipeline attributesPipeline;  // same lighting, plus the position record (tests)
  static GBufferLightingPass create(gpu::Device& device, VkPipelineLayout layout, uint32_t windowed);
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, const VkDescriptorSet* sets, uint32_t width, uint32_t height,
              bool writeAttributes) const;
};

}  // namespace visbuf::passes
