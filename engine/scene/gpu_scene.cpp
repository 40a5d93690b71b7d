#include "visbuf/scene/gpu_scene.h"

#include <algorithm>

#include <fmt/format.h>

namespace visbuf {

namespace {
uint32_t materialFlagsOf(const Material& m) {
  return (m.alphaMode == AlphaMode::Mask ? MATERIAL_FLAG_MASK : 0u) |
         (m.alphaMode == AlphaMode::Blend ? MATERIAL_FLAG_BLEND : 0u) | (m.doubleSided ? MATERIAL_FLAG_DOUBLE_SIDED : 0u);
}
}  // namespace

gpu::ObjectData packObject(const Object& object, const Scene& scene) {
  gpu::ObjectData d{};
  const glm::dmat4& m = object.transform;
  const glm::dvec3 t = glm::dvec3(m[3]) - scene.anchor;
  d.row0 = glm::vec4(float(m[0][0]), float(m[1][0]), float(m[2][0]), float(t.x));
  d.row1 = glm::vec4(float(m[0][1]), float(m[1][1]), float(m[2][1]), float(t.y));
  d.row2 = glm::vec4(float(m[0][2]), float(m[1][2]), float(m[2][2]), float(t.z));
  d.meshIndex = object.mesh;
  d.materialIndex = object.material;
  d.maxScale = float(maxScaleOf(m) * (1.0 + 1e-6));
  // Mirrored instances keep their front faces front: the raster culls them from the other side.
  d.flags = glm::determinant(glm::dmat3(m)) < 0.0 ? OBJECT_FLAG_FLIP_WINDING : 0u;
  const uint32_t materialFlags =
      object.material < scene.materials.size() ? materialFlagsOf(scene.materials[object.material]) : 0u;
  const uint32_t list = gpu::drawListOf(d.flags, materialFlags);
  d.flags |= (list == DRAW_LIST_NONE ? 15u : list) << OBJECT_DRAW_LIST_SHIFT;
  return d;
}

gpu::MaterialData packMaterial(const Material& m, const Scene& scene) {
  gpu::MaterialData d{};
  d.baseColor = m.baseColor;
  d.emissive = glm::vec4(m.emissive * m.emissiveStrength, m.normalScale);
  d.params = glm::vec4(m.metallic, m.roughness, m.occlusionStrength, m.alphaCutoff);
  d.flags = materialFlagsOf(m);
  const auto slots = textureSlots(m);
  for (size_t i = 0; i < kTextureSlotCount; ++i) {
    const TextureRef& t = *slots[i];
    gpu::TextureSlotData& x = d.textures[i];
    x.image = TEXTURE_NONE;
    x.transform01 = glm::vec4(t.transform[0], t.transform[1]);
    x.transform2 = glm::vec4(t.transform[2], 0.0f, 0.0f);
    x.samplerBits = uint32_t(t.sampler.wrapS) << TEXTURE_SAMPLER_WRAP_S_SHIFT |
                uint32_t(t.sampler.wrapT) << TEXTURE_SAMPLER_WRAP_T_SHIFT |
                (t.sampler.magFilter == TextureFilter::Linear ? TEXTURE_SAMPLER_MAG_LINEAR : 0u) |
                (t.sampler.minFilter == TextureFilter::Linear ? TEXTURE_SAMPLER_MIN_LINEAR : 0u) |
                uint32_t(t.sampler.mipFilter) << TEXTURE_SAMPLER_MIP_SHIFT | t.texCoord << TEXTURE_SAMPLER_TEXCOORD_SHIFT;
    if (t.baked >= 0 && size_t(t.baked) < scene.textures.size()) {
      const Texture& tex = scene.textures[size_t(t.baked)];
      x.image = tex.sizeClass << 16 | tex.layer;
      d.slotCount = uint32_t(i + 1);
    }
  }
  return d;
}

gpu::ObjectData packSkinnedObject(const Object& object, const glm::dmat4& placement, const Scene& scene) {
  Object placed = object;
  placed.transform = placement;
  return packObject(placed, scene);
}

uint32_t vertexWindowShift(uint64_t maxRange) {
  uint32_t shift = 3;  // 8 vertices = 256 bytes at least
  while (shift < 31 && (uint64_t(sizeof(gpu::Vertex)) << (shift + 1)) <= maxRange) ++shift;
  return shift;
}

uint32_t objectWindowSplit(uint64_t maxRange, uint32_t objectCount) {
  const uint64_t perWindow = maxRange / sizeof(gpu::ObjectData) / 4 * 4;
  return uint32_t(std::min<uint64_t>(objectCount, perWindow));
}

Result<GpuScene> uploadScene(gpu::Device& device, const Scene& scene) {
  Status valid = validateScene(scene);
  if (!valid) return valid.error();
  GpuScene g;
  if (scene.textureClasses.size() > MAX_TEXTURE_CLASSES)
    return makeError(ErrorCode::CapacityExceeded,
                     fmt::format("the scene has {} texture size classes, over the {} the shading pass binds",
                                 scene.textureClasses.size(), MAX_TEXTURE_CLASSES));
  std::vector<gpu::Vertex> vertices;
  std::vector<uint32_t> indices;
  std::vector<gpu::VertexExtra> extras;
  std::vector<glm::vec4> planes;  // per triangle of `indices` (all LODs): object-space unit normal, offset
  for (const Mesh& mesh : scene.meshes) {
    gpu::MeshData md{};
    md.boundsSphere = mesh.boundsSphere;
    md.vertexOffset = uint32_t(vertices.size());
    md.vertexCount = uint32_t(mesh.vertices.size());
    md.lodCount = uint32_t(mesh.lods.size());
    md.extraOffset = EXTRA_NONE;
    if (!mesh.tangents.empty() || !mesh.uvs1.empty()) {
      md.extraOffset = uint32_t(extras.size());
      for (size_t v = 0; v < mesh.vertices.size(); ++v) {
        gpu::VertexExtra e{};
        if (!mesh.tangents.empty() && mesh.tangents[v].w != 0.0f) {
          e.tangent = octEncode(glm::normalize(glm::vec3(mesh.tangents[v])));
          e.tangentW = mesh.tangents[v].w < 0.0f ? -1.0f : 1.0f;
        }
        if (!mesh.uvs1.empty()) {
          e.u1 = mesh.uvs1[v].x;
          e.v1 = mesh.uvs1[v].y;
        }
        extras.push_back(e);
      }
    }
    for (size_t l = 0; l < mesh.lods.size(); ++l)
      md.lods[l] = {uint32_t(indices.size()) + mesh.lods[l].firstIndex, mesh.lods[l].indexCount, mesh.lods[l].error, 0};
    g.maxTrianglesPerDraw = std::max(g.maxTrianglesPerDraw, mesh.triangleCount(0));
    vertices.insert(vertices.end(), mesh.vertices.begin(), mesh.vertices.end());
    indices.insert(indices.end(), mesh.indices.begin(), mesh.indices.end());
    // Only lavapipe's micro-raster reads them (sw_raster_cpu.comp); a GPU gets a 16-byte stand-in.
    for (size_t i = 0; device.isCpu() && i + 2 < mesh.indices.size(); i += 3) {
      const glm::dvec3 p0(mesh.position(mesh.indices[i])), p1(mesh.position(mesh.indices[i + 1])),
          p2(mesh.position(mesh.indices[i + 2]));
      const glm::dvec3 n = glm::cross(p1 - p0, p2 - p0);
      const double len = glm::length(n);
      planes.push_back(len > 0.0 ? glm::vec4(glm::vec3(n / len), float(-glm::dot(n / len, p0))) : glm::vec4(0.0f));
    }
    g.meshTable.push_back(md);
  }
  std::vector<gpu::ObjectData> objects;
  objects.reserve(scene.objects.size());
  for (const Object& o : scene.objects) objects.push_back(packObject(o, scene));
  for (uint32_t i = 0; i < scene.objects.size(); ++i) g.objectMesh.push_back(scene.objects[i].mesh);
  // Skinned instances: a region of skinned vertices each (position and normal; tangents where the mesh has
  // them) and a mesh slot of their own that keeps the rest mesh's vertices (uv, colour); the skin vertices of
  // each source mesh once.
  std::vector<SkinVertex> skinVertices;
  std::vector<int64_t> skinVertexStart(scene.meshes.size(), -1);
  std::vector<gpu::MorphDelta> morphDeltas;
  std::vector<int64_t> morphDeltaStart(scene.meshes.size(), -1);
  for (const SkinnedObject& so : scene.skinnedObjects) {
    const Object& o = scene.objects[so.object];
    const Mesh& mesh = scene.meshes[o.mesh];
    if (skinVertexStart[o.mesh] < 0) {
      skinVertexStart[o.mesh] = int64_t(skinVertices.size());
      skinVertices.insert(skinVertices.end(), mesh.skinVertices.begin(), mesh.skinVertices.end());
    }
    GpuScene::SkinnedRegion r;
    r.object = so.object;
    r.sourceMesh = o.mesh;
    r.meshSlot = uint32_t(g.meshTable.size());
    r.sourceVertex = g.meshTable[o.mesh].vertexOffset;
    r.skinVertex = uint32_t(skinVertexStart[o.mesh]);
    r.sourceExtra = g.meshTable[o.mesh].extraOffset;
    r.vertexCount = uint32_t(mesh.vertices.size());
    r.hasTangents = !mesh.tangents.empty();
    if (so.morphNode >= 0 && mesh.morphTargetCount > 0) {
      if (morphDeltaStart[o.mesh] < 0) {
        morphDeltaStart[o.mesh] = int64_t(morphDeltas.size());
        morphDeltas.insert(morphDeltas.end(), mesh.morphDeltas.begin(), mesh.morphDeltas.end());
      }
      if (morphDeltas.size() > UINT32_MAX)
        return makeError(ErrorCode::CapacityExceeded, "more than 2^32-1 morph deltas in the skinned meshes");
      r.morphTargets = mesh.morphTargetCount;
      r.firstMorphDelta = uint32_t(morphDeltaStart[o.mesh]);
    }
    g.meshTable.push_back(g.meshTable[o.mesh]);  // addresses once the buffers exist
    objects[so.object] = packSkinnedObject(o, so.placement, scene);
    objects[so.object].meshIndex = r.meshSlot;
    g.objectMesh[so.object] = r.meshSlot;
    g.skinned.push_back(r);
  }
  std::vector<gpu::MaterialData> materials;
  for (const Material& m : scene.materials) materials.push_back(packMaterial(m, scene));
  g.objectList.reserve(objects.size());
  for (const gpu::ObjectData& o : objects) g.objectList.push_back(gpu::objectDrawList(o.flags));

  const uint64_t limit = device.properties().limits.maxStorageBufferRange;
  auto check = [&](const char* what, uint64_t bytes) -> Status {
    if (bytes > limit)
      return makeError(ErrorCode::CapacityExceeded,
                       fmt::format("{} buffer needs {:.1f} MiB, over this device's maxStorageBufferRange of "
                                   "{:.1f} MiB", what, bytes / 1048576.0, limit / 1048576.0));
    return {};
  };
  // The vertex pool: VERTEX_WINDOWS windows, and one buffer of at most the device's maxBufferSize.
  VkPhysicalDeviceVulkan11Properties p11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_PROPERTIES};
  VkPhysicalDeviceVulkan13Properties p13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_PROPERTIES};
  VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  p2.pNext = &p13;
  p13.pNext = &p11;
  vkGetPhysicalDeviceProperties2(device.physicalDevice(), &p2);
  const uint64_t poolLimit = std::min<uint64_t>(uint64_t(sizeof(gpu::Vertex)) << vertexWindowShift(limit) << 2,
                                                p13.maxBufferSize);
  if (vertices.size() * sizeof(gpu::Vertex) > poolLimit)
    return makeError(ErrorCode::CapacityExceeded,
                     fmt::format("vertex pool needs {:.1f} MiB, over this device's {:.1f} MiB ({} descriptor windows "
                                 "of maxStorageBufferRange, or maxBufferSize)",
                                 vertices.size() * sizeof(gpu::Vertex) / 1048576.0, poolLimit / 1048576.0,
                                 VERTEX_WINDOWS));
  // Skinned regions: packed in order into blocks of at most one buffer (maxBufferSize, maxMemoryAllocationSize:
  // 2 GiB on lavapipe); each mesh slot holds its region's full address, so the blocks need not be contiguous.
  const uint64_t blockLimit = std::min<uint64_t>(p13.maxBufferSize, p11.maxMemoryAllocationSize);
  std::vector<uint64_t> blockBytes;
  for (GpuScene::SkinnedRegion& r : g.skinned) {
    const uint64_t v = uint64_t(r.vertexCount) * sizeof(gpu::SkinnedVertex);
    const uint64_t t = r.hasTangents ? (uint64_t(r.vertexCount) * sizeof(uint32_t) + 15) / 16 * 16 : 0;
    if (v + t > blockLimit)
      return makeError(ErrorCode::CapacityExceeded,
                       fmt::format("skinned mesh {} needs {:.1f} MiB per instance, over this device's {:.1f} MiB "
                                   "for one buffer (maxBufferSize, maxMemoryAllocationSize)",
                                   r.sourceMesh, (v + t) / 1048576.0, blockLimit / 1048576.0));
    if (blockBytes.empty() || blockBytes.back() + v + t > blockLimit) blockBytes.push_back(0);
    r.block = uint32_t(blockBytes.size() - 1);
    r.vertexBytes = blockBytes.back();
    r.tangentBytes = t ? r.vertexBytes + v : 0;
    blockBytes.back() += v + t;
  }
  for (auto [what, bytes] : {
                             std::pair{"index", indices.size() * sizeof(uint32_t)},
                             std::pair{"vertex extras (tangents, TEXCOORD_1)", extras.size() * sizeof(gpu::VertexExtra)},
                             std::pair{"object (second window)",
                                       (objects.size() - objectWindowSplit(limit, uint32_t(objects.size()))) *
                                           sizeof(gpu::ObjectData)}}) {
    Status s = check(what, bytes);
    if (!s) return s.error();
  }
  const VkBufferUsageFlags ssbo = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  const VkBufferUsageFlags texel = VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT;
  g.vertices = gpu::uploadVector(device, vertices, ssbo | texel);
  g.indices = gpu::uploadVector(device, indices, ssbo | texel | VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
  for (uint64_t bytes : blockBytes)  // contents written by the skinning pass before any frame reads them
    g.skinnedVertices.emplace_back(device, bytes,
                                   ssbo | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                   gpu::MemoryUse::DeviceLocal);
  uint64_t skinnedBytes = 0;
  for (const gpu::Buffer& b : g.skinnedVertices) skinnedBytes += b.size();
  for (const GpuScene::SkinnedRegion& r : g.skinned) {
    gpu::MeshData& md = g.meshTable[r.meshSlot];
    const VkDeviceAddress base = g.skinnedVertices[r.block].address();
    const VkDeviceAddress v = base + r.vertexBytes, t = r.tangentBytes ? base + r.tangentBytes : 0;
    md.skinnedVertexLow = uint32_t(v);
    md.skinnedVertexHigh = uint32_t(v >> 32);
    md.skinnedTangentLow = uint32_t(t);
    md.skinnedTangentHigh = uint32_t(t >> 32);
  }
  g.meshes = gpu::uploadVector(device, g.meshTable, ssbo | texel | VK_BUFFER_USAGE_TRANSFER_SRC_BIT);
  g.objects = gpu::uploadVector(device, objects, ssbo | texel);
  g.trianglePlanes = gpu::uploadVector(device, planes, texel);
  g.materials = gpu::uploadVector(device, materials, ssbo | texel);
  {
    const VkDeviceSize maxTexels = device.properties().limits.maxTexelBufferElements;
    auto view = [&](const gpu::Buffer& b, VkFormat format, VkDeviceSize texelBytes) {
      const VkDeviceSize range = std::min(b.size() / texelBytes, maxTexels) * texelBytes;
      return gpu::BufferView(device, b, format, 0, std::max(range, texelBytes));
    };
    g.vertexTexels = view(g.vertices, VK_FORMAT_R32G32B32A32_UINT, 16);
    g.indexTexels = view(g.indices, VK_FORMAT_R32_UINT, 4);
    g.objectTexels = view(g.objects, VK_FORMAT_R32G32B32A32_UINT, 16);
    g.planeTexels = view(g.trianglePlanes, VK_FORMAT_R32G32B32A32_SFLOAT, 16);
    static_assert(sizeof(gpu::MeshData) == (3 + MAX_LODS) * 16, "common.glsl MESH_TEXELS");
    g.meshTexels = view(g.meshes, VK_FORMAT_R32G32B32A32_UINT, 16);
    static_assert(sizeof(gpu::MaterialData) == (4 + 3 * TEXTURE_SLOTS) * 16, "common.glsl MATERIAL_TEXELS");
    g.materialTexels = view(g.materials, VK_FORMAT_R32G32B32A32_UINT, 16);
    g.texels = true;
    for (const gpu::Buffer* b : {&g.vertices, &g.objects, &g.trianglePlanes, &g.meshes, &g.materials})
      g.texels = g.texels && b->size() / 16 <= maxTexels;
    g.texels = g.texels && g.indices.size() / 4 <= maxTexels;
  }
  if (!skinVertices.empty()) g.skinVertices = gpu::uploadVector(device, skinVertices, ssbo);
  if (!morphDeltas.empty()) g.morphDeltas = gpu::uploadVector(device, morphDeltas, ssbo);
  g.vertexExtras = gpu::uploadVector(device, extras, ssbo);  // at least 16 bytes: always bindable
  uint64_t textureBytes = 0;
  for (const TextureClass& c : scene.textureClasses) {
    g.textureClasses.push_back(uploadTextureClass(device, c));
    textureBytes += c.texels.size();
  }
  TextureClass white;
  white.size = 1;
  white.layers = 1;
  white.mipCount = 1;
  white.texels = {255, 255, 255, 255};
  g.placeholderTexture = uploadTextureClass(device, white);
  g.objectCount = uint32_t(objects.size());
  g.bytes = g.vertices.size() + g.indices.size() + g.trianglePlanes.size() + g.meshes.size() + g.objects.size() + g.materials.size() +
            (g.skinVertices ? g.skinVertices.size() : 0) + (g.morphDeltas ? g.morphDeltas.size() : 0) + skinnedBytes + g.vertexExtras.size() +
            textureBytes;
  return g;
}

}  // namespace visbuf
