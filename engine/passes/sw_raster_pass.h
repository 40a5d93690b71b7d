// Software micro-raster (shaders/sw_raster.comp.glsl, sw_merge.{vert,frag}.glsl): the draws that the cull pass
// routed away from the hardware raster (small objects: FrameData.swRaster) are rasterised in compute into a 64-bit
// buffer per pixel (reverse-Z depth << 32 | payload, atomicMax), then merged into the visibility target and its
// depth by a full-screen pass that writes gl_FragDepth and is depth-tested GREATER like any raster fragment. Run
// after each raster phase; the pyramid, the late phase, the shading and the transparency pass see one target.
// Reads: frame, objects, meshes, vertices, indices, draws, draw counts (stats), draw lists. Writes: the buffer
// (cleared by the early/only phase), ID target, depth.
#pragma once

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::passes {

struct SwRasterPass {
  gpu::PassLayout layout;
  gpu::Pipeline raster;
  gpu::Pipeline merge[2];  // narrow (r32ui), wide (rg32ui)
  // The 64-bit per-pixel buffer: an 8-byte stand-in after resetBuffer (creation, resize), the frame's size once
  // ensureBuffer ran; ensureBuffer returns true when it allocated (its set to write again: bind).
  gpu::Buffer buffer;
  gpu::BufferView texels;  // the same as RG32UI texels (the merge and the shading's SW_RESOLVE variants read it)
  void resetBuffer(gpu::Device& device);
  bool ensureBuffer(gpu::Device& device, uint32_t width, uint32_t height);
  static SwRasterPass create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, const gpu::Specialization& spec);
  bool created() const { return raster.handle() != VK_NULL_HANDLE; }
  // Its set: the cull pass's draws and the draw lists, and its own buffer.
  void bind(const gpu::Buffer& draws, const gpu::Buffer& drawLists) const;
  // The raster dispatch and the merge draw take their sizes from the cull pass (config.h SW_ARGS in `stats`): a
  // phase that routed nothing here dispatches no workgroup and draws no triangle. Each workgroup loops over the
  // phase's routed draws.
  void recordRaster(VkCommandBuffer cmd, VkDescriptorSet scene, uint32_t phase, const gpu::Buffer& stats) const;
  // ids / depth: COLOR_ATTACHMENT_OPTIMAL / DEPTH_ATTACHMENT_OPTIMAL, loaded and stored.
  void recordMerge(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Image& ids, const gpu::Image& depth,
                   const gpu::Buffer& stats, uint32_t phase) const;

 private:
  bool sized_ = false;
};

}  // namespace visbuf::passes
