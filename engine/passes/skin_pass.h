// Skinning pass (shaders/skin.comp.glsl): linear blend skinning (up to 8 joint influences per vertex, the
// SkinVertex records of scene/skin_vertex.h) of every animated instance into its own
// region of the skinned-vertex buffer (addressed by its mesh slot), plus the instance's per-pose bounds and LOD
// errors in its mesh slot. Bounds: the CPU's joint-reach sphere, or (gpuBounds) an AABB reduced from the skinned
// vertices with atomics, whose centre and the largest distance of the vertices from it make the sphere (three
// more dispatches of the skin_bounds variant).
// Reads: rest vertices and tangents, skin vertices, morph deltas, joint rows (and morph weights), instance records. Writes: skinned regions,
// mesh slots, the bounds records.
// It has its own descriptor set (the frame's set never sees the skinning inputs); created only for scenes
// with skinned objects.
#pragma once

#include <array>

#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/shared/config.h"

namespace visbuf::passes {

struct SkinInputs {
  std::array<VkDescriptorBufferInfo, VERTEX_WINDOWS> vertexWindows{};  // the unified pool (rest vertices)
  VkBuffer meshes = VK_NULL_HANDLE;        // the mesh table (instance slots written)
  VkBuffer skinVertices = VK_NULL_HANDLE;  // SkinVertex[]
  VkBuffer joints = VK_NULL_HANDLE;        // vec4 rows, 3 per joint matrix
  VkBuffer instances = VK_NULL_HANDLE;     // gpu::SkinInstance[]
  VkBuffer vertexExtras = VK_NULL_HANDLE;  // gpu::VertexExtra[] (rest tangents)
  VkBuffer bounds = VK_NULL_HANDLE;        // SKIN_BOUNDS_UINTS per instance (gpuBounds), else any 16 bytes
  VkBuffer morphDeltas = VK_NULL_HANDLE;   // MorphDelta[] (scenes with morph targets), else any buffer
  bool gpuBounds = false;                  // bounds from the skinned vertices instead of the joints' reach
};

class SkinPass {
 public:
  SkinPass() = default;
  ~SkinPass();
  SkinPass(const SkinPass&) = delete;
  SkinPass& operator=(const SkinPass&) = delete;
  // vertexWindowShift: vertices per pool window, as FrameData::vertexWindowShift.
  void create(gpu::Device& device, const SkinInputs& inputs, uint32_t vertexWindowShift);
  // One dispatch over `instances` instances of at most `maxVertices` vertices each; with GPU bounds, a fill of
  // the bounds records before it and the three resolve dispatches (centre, distance, radius) after it.
  void record(VkCommandBuffer cmd, uint32_t instances, uint32_t maxVertices) const;

 private:
  gpu::Device* device_ = nullptr;
  VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  gpu::Pipeline pipeline_;
  gpu::Pipeline resolve_;  // skin_bounds.comp (gpuBounds only)
  uint32_t vertexWindowShift_ = 0;
  VkBuffer bounds_ = VK_NULL_HANDLE;
  bool gpuBounds_ = false;
};

}  // namespace visbuf::passes
