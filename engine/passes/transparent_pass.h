// Transparency pass (shaders/forward.vert.glsl + transparent variant of forward.frag.glsl): glTF BLEND objects
// drawn forward on top of the shaded colour image, back to front per object, depth-tested against the opaque
// depth (GREATER, reverse-Z) without writing it, premultiplied blending (colour = src + (1 - src.a) * dst).
// Recorded by the frame script only for scenes with BLEND materials, in both paths.
// Reads: frame, objects, vertices, index buffer, materials, depth. Writes: colour (blended).
#pragma once

#include <array>
#include <vector>

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/passes/forward_pass.h"

namespace visbuf::passes {

struct TransparentDraw {
  ForwardDraw draw;         // draw.list: the opaque list of the same raster state (face culling), 0..2
  double viewDepth = 0.0;   // distance of the bounds centre along the view direction (double precision)
};

// Back to front: largest view depth first; equal depths keep their order (stable), so frames are repeatable.
// Objects are sorted as wholes by their bounds centre: intersecting transparent objects, and an object's own
// overlapping triangles, are not sorted per triangle.
void sortBackToFront(std::vector<TransparentDraw>& draws);

class TransparentPass {
 public:
  static TransparentPass create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec);
  // Its set: the point lights and their tile lists (any buffers where the scene has none: never read then).
  void bind(const gpu::Buffer& lights, const gpu::Buffer& lightTiles) const;
  // color: rgba16f in COLOR_ATTACHMENT_OPTIMAL, loaded; depth: D32 in DEPTH_ATTACHMENT_OPTIMAL, loaded, not
  // written. draws: drawn in the given order (sortBackToFront).
  void record(VkCommandBuffer cmd, VkDescriptorSet scene, const gpu::Image& color,
              const gpu::Image& depth, VkBuffer indexBuffer, const std::vector<TransparentDraw>& draws) const;
  bool created() const { return pipelines_[0].handle() != VK_NULL_HANDLE; }

 private:
  gpu::PassLayout layout_;
  std::array<gpu::Pipeline, 3> pipelines_;  // per face-culling state: DRAW_LIST_OPAQUE, _FLIPPED, _DOUBLE_SIDED
};

}  // namespace visbuf::passes
