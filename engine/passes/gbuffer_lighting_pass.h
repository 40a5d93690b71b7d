// G-buffer baseline lighting (shaders/gbuffer_lighting.comp.glsl): one thread per pixel reads the attribute
// targets (BINDING_GBUFFER) and the depth (BINDING_GBUFFER_DEPTH), rebuilds the camera-relative position from the
// depth and calls shadeSurface(). Reads: frame, the targets, depth. Writes: colour (rgba16f, GENERAL), covered
// pixels only (the frame script clears it to the background first, as for shade_pass).
#pragma once

#include "gpu/pipeline.h"

namespace visbuf::passes {

struct GBufferLightingPass {
  gpu::Pipeline pipeline;
  static GBufferLightingPass create(gpu::Device& device, VkPipelineLayout layout, uint32_t windowed);
  void record(VkCommandBuffer cmd, VkPipelineLayout layout, VkDescriptorSet set, uint32_t width,
              uint32_t height) const;
};

}  // namespace visbuf::passes
