#include "visbuf/render/scene_descriptors.h"

#include <algorithm>
#include <vector>

#include "visbuf/gpu/pipeline.h"

namespace visbuf {

std::array<VkDescriptorBufferInfo, VERTEX_WINDOWS> vertexWindows(const gpu::Buffer& pool, uint32_t shift) {
  const VkDeviceSize window = VkDeviceSize(sizeof(gpu::Vertex)) << shift;
  std::array<VkDescriptorBufferInfo, VERTEX_WINDOWS> w{};
  for (uint32_t k = 0; k < VERTEX_WINDOWS; ++k) {
    const VkDeviceSize offset = k * window;
    w[k] = offset < pool.size() ? VkDescriptorBufferInfo{pool.handle(), offset, std::min(window, pool.size() - offset)}
                                : VkDescriptorBufferInfo{pool.handle(), 0, std::min(window, pool.size())};
  }
  return w;
}

void SceneDescriptors::create(gpu::Device& device, uint32_t slots) {
  constexpr VkDescriptorType storage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  constexpr VkDescriptorType texels = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
  sets_ = gpu::DescriptorLayout(device,
                                {{SCENE_BINDING_FRAME, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
                                 {SCENE_BINDING_OBJECTS, storage},
                                 {SCENE_BINDING_OBJECTS_HIGH, storage},
                                 {SCENE_BINDING_MESHES, storage},
                                 {SCENE_BINDING_VERTICES, storage},
                                 {SCENE_BINDING_VERTICES_1, storage},
                                 {SCENE_BINDING_VERTICES_2, storage},
                                 {SCENE_BINDING_VERTICES_3, storage},
                                 {SCENE_BINDING_INDICES, storage},
                                 {SCENE_BINDING_MATERIALS, storage},
                                 {SCENE_BINDING_VERTEX_EXTRAS, storage},
                                 {SCENE_BINDING_TEXTURE_CLASSES, VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE, MAX_TEXTURE_CLASSES},
                                 {SCENE_BINDING_VERTEX_TEXELS, texels},
                                 {SCENE_BINDING_TRIANGLE_TEXELS, texels},
                                 {SCENE_BINDING_OBJECT_TEXELS, texels},
                                 {SCENE_BINDING_MESH_TEXELS, texels},
                                 {SCENE_BINDING_MATERIAL_TEXELS, texels},
                                 {SCENE_BINDING_TRIANGLE_PLANES, texels},
                                 {SCENE_BINDING_STATS, storage}},
                                gpu::kPassConstantStages, slots);
}

void SceneDescriptors::write(uint32_t slot, const gpu::Buffer& frame, const SceneSetInputs& in) const {
  const GpuScene& s = *in.scene;
  // Objects: two windows of one buffer, split where one descriptor range would end (objectWindowSplit).
  const VkDeviceSize lowBytes = VkDeviceSize(in.objectSplit) * sizeof(gpu::ObjectData);
  const bool highUsed = in.objectSplit < s.objectCount;
  const std::array<VkDescriptorBufferInfo, VERTEX_WINDOWS> vw = vertexWindows(s.vertices, in.vertexShift);
  // Texture classes: the scene's, then the placeholder in every unused slot (material.glsl).
  std::vector<VkDescriptorImageInfo> textures(MAX_TEXTURE_CLASSES);
  for (size_t i = 0; i < textures.size(); ++i) {
    const gpu::Image& t = i < s.textureClasses.size() ? s.textureClasses[i] : s.placeholderTexture;
    textures[i] = {VK_NULL_HANDLE, t.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  }
  gpu::DescriptorWriter(sets_, slot)
      .buffer(SCENE_BINDING_FRAME, frame.handle())
      .buffer(SCENE_BINDING_OBJECTS, {s.objects.handle(), 0, highUsed ? lowBytes : VK_WHOLE_SIZE})
      .buffer(SCENE_BINDING_OBJECTS_HIGH, {s.objects.handle(), highUsed ? lowBytes : 0, VK_WHOLE_SIZE})
      .buffer(SCENE_BINDING_MESHES, s.meshes.handle())
      .buffer(SCENE_BINDING_VERTICES, vw[0])
      .buffer(SCENE_BINDING_VERTICES_1, vw[1])
      .buffer(SCENE_BINDING_VERTICES_2, vw[2])
      .buffer(SCENE_BINDING_VERTICES_3, vw[3])
      .buffer(SCENE_BINDING_INDICES, s.indices.handle())
      .buffer(SCENE_BINDING_MATERIALS, s.materials.handle())
      .buffer(SCENE_BINDING_VERTEX_EXTRAS, s.vertexExtras.handle())
      .images(SCENE_BINDING_TEXTURE_CLASSES, std::move(textures))
      .texels(SCENE_BINDING_VERTEX_TEXELS, s.vertexTexels.handle())
      .texels(SCENE_BINDING_TRIANGLE_TEXELS, s.triangleTexels.handle())
      .texels(SCENE_BINDING_OBJECT_TEXELS, s.objectTexels.handle())
      .texels(SCENE_BINDING_MESH_TEXELS, s.meshTexels.handle())
      .texels(SCENE_BINDING_MATERIAL_TEXELS, s.materialTexels.handle())
      .texels(SCENE_BINDING_TRIANGLE_PLANES, s.planeTexels.handle())
      .buffer(SCENE_BINDING_STATS, in.stats->handle())
      .update();
}

}  // namespace visbuf
