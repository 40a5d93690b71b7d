// Tiled light culling (shaders/light_cull.comp.glsl): one thread per 16x16 screen tile builds the list of the
// KHR_lights_punctual lights that can reach a covered pixel of the tile, from the tile's depth bounds in the
// visibility depth: point and spot lights by their range sphere; directional lights are in every covered tile.
// Reads: frame, point lights, depth (shader-read layout).
// Writes: the tile lists and their counters (layout in shaders/shared/config.h).
// Created only for scenes with point lights; a scene without any records no light culling and owns no light
// buffers.
#pragma once

#include <cstdint>

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::passes {

struct LightCullStats {
  uint32_t overflowTiles = 0;  // tiles whose list hit LIGHTS_PER_TILE (their extra lights were dropped)
  uint32_t droppedLights = 0;  // (tile, light) pairs dropped for lack of capacity
  uint32_t maxPerTile = 0;     // the longest list before clamping
  uint32_t pairs = 0;          // (tile, light) pairs kept
};

class LightCullPass {
 public:
  void create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, uint32_t windowed);
  // (Re)allocates the tile lists for a width x height frame.
  void resize(gpu::Device& device, uint32_t width, uint32_t height);
  // Its set: the point lights, the depth the tile bounds come from (the multisampled one in MSAA frames) and its
  // tile lists (after resize).
  void bind(const gpu::Buffer& lights, const gpu::Image& depth, VkSampler sampler) const;
  // Resets the counters, then one dispatch over every tile. The depth must be in SHADER_READ_ONLY_OPTIMAL.
  // multisampled: the bound depth is the MSAA depth; the bounds take every sample.
  void record(VkCommandBuffer cmd, VkDescriptorSet scene, bool multisampled = false) const;
  // After record: copies the counters to a host-visible buffer (transfer stage), read by stats().
  void recordReadback(VkCommandBuffer cmd) const;
  LightCullStats stats() const;
  const gpu::Buffer& tiles() const { return tiles_; }
  uint32_t tilesX() const { return tilesX_; }
  uint32_t tilesY() const { return tilesY_; }

 private:
  gpu::PassLayout layout_;
  gpu::Pipeline pipeline_;
  gpu::Pipeline msaaPipeline_;
  gpu::Buffer tiles_;     // uint[LIGHT_TILE_HEADER + tiles * LIGHT_TILE_STRIDE]
  gpu::Buffer readback_;  // the header
  uint32_t tilesX_ = 0, tilesY_ = 0;
};

}  // namespace visbuf::passes
