// Object-record upload (shaders/object_scatter.comp.glsl): the frame's changed object records, staged on the host
// with their object IDs, scattered into the scene's object buffer by one compute dispatch. Reads: the staging
// buffer (host-written). Writes: the object buffer. Buffers are passed by device address; the pass owns its
// pipeline layout (push constants only, no descriptor set).
#pragma once

#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::passes {

class ObjectUploadPass {
 public:
  ObjectUploadPass() = default;
  ~ObjectUploadPass();
  ObjectUploadPass(const ObjectUploadPass&) = delete;
  ObjectUploadPass& operator=(const ObjectUploadPass&) = delete;
  void create(gpu::Device& device);
  // staging: `count` 64-byte records from byte 0, then `count` uint32 object IDs at byte `idsOffset`; objects:
  // the object buffer. Both created with VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT.
  void record(VkCommandBuffer cmd, const gpu::Buffer& staging, VkDeviceSize idsOffset, const gpu::Buffer& objects,
              uint32_t count) const;

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  gpu::Pipeline pipeline_;
};

}  // namespace visbuf::passes
