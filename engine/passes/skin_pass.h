// Skinning pass (shaders/skin.comp.glsl): linear blend skinning of every animated instance into its own
// region of the unified vertex pool, plus the instance's per-pose bounds and LOD errors in its mesh slot.
// Reads: rest vertices, skin vertices, joint rows, instance records. Writes: vertex regions, mesh slots.
// It has its own descriptor set (the frame's set never sees the skinning inputs); created only for scenes
// with skinned objects.
#pragma once

#include <array>

#include "gpu/pipeline.h"
#include "gpu/resources.h"
#include "shared/config.h"

namespace visbuf::passes {

struct SkinInputs {
  std::array<VkDescriptorBufferInfo, VERTEX_WINDOWS> vertexWindows{};  // the unified pool (read and written)
  VkBuffer meshes = VK_NULL_HANDLE;        // the mesh table (instance slots written)
  VkBuffer skinVertices = VK_NULL_HANDLE;  // SkinVertex[]
  VkBuffer joints = VK_NULL_HANDLE;        // vec4 rows, 3 per joint matrix
  VkBuffer instances = VK_NULL_HANDLE;     // gpu::SkinInstance[]
};

class SkinPass {
 public:
  SkinPass() = default;
  ~SkinPass();
  SkinPass(const SkinPass&) = delete;
  SkinPass& operator=(const SkinPass&) = delete;
  // vertexWindowShift: vertices per pool window, as FrameData::vertexWindowShift.
  void create(gpu::Device& device, const SkinInputs& inputs, uint32_t vertexWindowShift);
  // One dispatch over `instances` instances of at most `maxVertices` vertices each.
  void record(VkCommandBuffer cmd, uint32_t instances, uint32_t maxVertices) const;

 private:
  gpu::Device* device_ = nullptr;
  VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  gpu::Pipeline pipeline_;
  uint32_t vertexWindowShift_ = 0;
};

}  // namespace visbuf::passes
