// Material classification and classified shading: the alternative to the single "ubershader" dispatch of the
// shading pass (shade_pass). Per frame, on the GPU:
//   classify_count.comp    one workgroup per 8x8 shading tile: the materials present, per material +1 tile and
//                          its pixel count (the MaterialTiles records);
//   classify_scan.comp     exclusive prefix sum of the tile counts: each material's first tile-list entry, and
//                          its VkDispatchIndirectCommand (its tiles in rows of CLASSIFY_DISPATCH_WIDTH);
//   classify_scatter.comp  each tile appended to the list of every material present in it (the tile list);
//   shade_classified.comp  one vkCmdDispatchIndirect per material (push constant: the material), one workgroup
//                          per listed tile; lanes showing another material leave. Each material uses the
//                          pipeline of its Variant: untextured (no sampling code) without a texture, and only the
//                          shading features it has (unlit, clearcoat: VB_MATERIAL_FEATURES), so a material pays for
//                          no other's code; a material with no pixels gets 0 workgroups.
// Reads: frame, IDs (SHADER_READ_ONLY_OPTIMAL), draws, objects; shading as shade_pass. Writes: the colour image
// (GENERAL, cleared to the background before), the classification buffers.
#pragma once

#include <compare>
#include <cstdint>
#include <map>
#include <vector>

#include "visbuf/gpu/descriptors.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/passes/shade_pass.h"

namespace visbuf::passes {

struct ClassifyStats {
  uint32_t pairs = 0;             // (tile, material) pairs listed = workgroups of all shading dispatches
  uint32_t materialsPresent = 0;  // materials with at least one pixel
  std::vector<uint32_t> tiles;    // per material: tiles holding its pixels
  std::vector<uint32_t> pixels;   // per material: its pixels
};

class ClassifyPass {
 public:
  // What a material's dispatch needs of the shading pipeline.
  struct Variant {
    bool textured = false;     // samples a texture (with spec.textureClasses == 0 none does)
    uint32_t features = 0;     // MATERIAL_FEATURE_* bits (scene.h materialFeatures)
    auto operator<=>(const Variant&) const = default;
  };
  // variants[m]: material m's; one shading pipeline is created per distinct variant.
  void create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec,
              std::vector<Variant> variants);
  bool created() const { return !variants_.empty(); }
  // (Re)allocates the tile list for a width x height frame: tiles x min(materials, 64) entries.
  void resize(gpu::Device& device, uint32_t width, uint32_t height);
  // Its set: the shading set (the same inputs as the shading pass) and its own buffers (after resize).
  void bind(const ShadeInputs& shading) const;
  // Count, scan and scatter, then the barrier to the indirect dispatches and a copy of the records for stats().
  void recordClassify(VkCommandBuffer cmd, VkDescriptorSet scene) const;
  // The shading dispatches, one per material.
  void recordShade(VkCommandBuffer cmd, VkDescriptorSet scene) const;
  ClassifyStats stats() const;  // after the frame's fence
  uint64_t bytes() const { return materialTiles_.size() + tileList_.size(); }

 private:
  gpu::PassLayout layout_;
  gpu::Pipeline count_, scan_, scatter_;
  std::map<Variant, gpu::Pipeline> shade_;  // one per distinct variant
  std::vector<Variant> variants_;          // per material
  gpu::Buffer materialTiles_;    // CLASSIFY_HEADER uints + MaterialTiles[materials]
  gpu::Buffer readback_;         // its copy
  gpu::Buffer tileList_;         // uint[tiles x min(materials, 64)]
  uint32_t tilesX_ = 0, tilesY_ = 0;
};

}  // namespace visbuf::passes
