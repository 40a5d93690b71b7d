// G-buffer baseline lighting (shaders/gbuffer_lighting.comp.glsl): one thread per pixel reads the attribute
// targets and the depth, rebuilds the camera-relative position from the depth and calls shadeSurface(). Reads:
// frame, the targets, depth. Writes: colour (rgba16f, GENERAL), covered pixels only (the frame script clears it to
// the background first, as for shade_pass); the attributes variant also writes the rebuilt position and depth to
// the attribute buffer (slots 0..3 of config.h's record, 7 = 1).
#pragma once

#include <array>

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/shared/config.h"

namespace visbuf::passes {

struct GBufferLightingInputs {
  const gpu::Buffer* lights = nullptr;      // point lights (any buffer where the scene has none: never read then)
  const gpu::Buffer* lightTiles = nullptr;  // their tile lists (likewise)
  std::array<const gpu::Image*, GBUFFER_TARGETS> targets{};  // shader-read layout
  const gpu::Image* depth = nullptr;        // the frame's D32 depth (reverse-Z), shader-read layout
  VkSampler sampler = VK_NULL_HANDLE;       // nearest
  const gpu::Image* color = nullptr;        // rgba16f, GENERAL
  const gpu::Buffer* attributes = nullptr;
};

struct GBufferLightingPass {
  gpu::PassLayout layout;
  gpu::Pipeline pipeline;
  gpu::Pipeline attributesPipeline;  // same lighting, plus the position record (tests)
  // materialFeatures: MATERIAL_FEATURE_* bits of the scene's materials (gpu::Specialization).
  static GBufferLightingPass create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, uint32_t windowed,
                                    uint32_t materialFeatures);
  bool created() const { return bool(layout); }
  void bind(const GBufferLightingInputs& in) const;
  void record(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t width, uint32_t height, bool writeAttributes) const;
};

}  // namespace visbuf::passes
