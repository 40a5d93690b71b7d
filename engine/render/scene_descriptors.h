// The scene set (set 0 of every frame pass, config.h SCENE_BINDING_*): the frame's uniforms and the scene data that
// nearly every pass reads, one set per frame slot (each slot has its own FrameData buffer).
#pragma once

#include <array>
#include <cstdint>

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/scene/gpu_scene.h"
#include "visbuf/shared/config.h"

namespace visbuf {

// The vertex pool's descriptor windows: window k covers vertices [k << shift, (k + 1) << shift); windows past
// the end of the pool repeat window 0 (bound, never read).
std::array<VkDescriptorBufferInfo, VERTEX_WINDOWS> vertexWindows(const gpu::Buffer& pool, uint32_t shift);

// What the scene set holds besides the frame buffer.
struct SceneSetInputs {
  const GpuScene* scene = nullptr;
  const gpu::Buffer* stats = nullptr;  // the frame-wide counters
  uint32_t objectSplit = 0;            // first object of the high window (objectWindowSplit)
  uint32_t vertexShift = 0;            // vertices per vertex-pool window: 1 << vertexShift
};

class SceneDescriptors {
 public:
  void create(gpu::Device& device, uint32_t slots);
  VkDescriptorSetLayout layout() const { return sets_.layout(); }
  VkDescriptorSet set(uint32_t slot) const { return sets_.set(slot); }
  // Writes the slot's set: its FrameData buffer and the scene's.
  void write(uint32_t slot, const gpu::Buffer& frame, const SceneSetInputs& in) const;

 private:
  gpu::DescriptorLayout sets_;
};

}  // namespace visbuf
