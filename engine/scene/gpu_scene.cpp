#include "visbuf/scene/gpu_scene.h"
#include "visbuf/scene/clusters.h"


#include <algorithm>
#include <cstring>

#include <fmt/format.h>

namespace visbuf {

namespace {

// Host-to-device copies through one reused staging buffer: writes are packed into it, and when it is full its
// copies are submitted and waited for (a fence wait per chunk) before it is refilled. Host memory for an upload is
// the staging buffer, whatever the size of the data.
class StagingUploader {
 public:
  StagingUploader(gpu::Device& device, VkDeviceSize capacity)
      : device_(device),
        staging_(device, std::max<VkDeviceSize>(capacity, 16), VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                 gpu::MemoryUse::HostVisible) {}
  // Pending copies are dropped, not submitted: the upload that keeps its buffers calls release(); one abandoned on
  // an error (returned, or a Vulkan failure unwinding) may already have destroyed the buffers they target.
  ~StagingUploader() = default;
  StagingUploader(const StagingUploader&) = delete;
  StagingUploader& operator=(const StagingUploader&) = delete;

  VkDeviceSize capacity() const { return staging_.size(); }

  // Copies `bytes` from `src` (null: zeros) to `dst` at `offset`, in chunks of at most the staging size.
  void write(const gpu::Buffer& dst, VkDeviceSize offset, const void* src, size_t bytes) {
    const auto* from = static_cast<const uint8_t*>(src);
    while (bytes > 0) {
      if (used_ == staging_.size()) flush();  // the chunk is full: copy it out, then reuse it
      const size_t n = size_t(std::min<VkDeviceSize>(bytes, staging_.size() - used_));
      uint8_t* to = static_cast<uint8_t*>(staging_.mapped()) + used_;
      if (from) {
        std::memcpy(to, from, n);
        from += n;
      } else {
        std::memset(to, 0, n);
      }
      if (!copies_.empty() && copies_.back().dst == dst.handle() &&
          copies_.back().region.dstOffset + copies_.back().region.size == offset &&
          copies_.back().region.srcOffset + copies_.back().region.size == used_) {
        copies_.back().region.size += n;  // contiguous with the previous write: one region
      } else {
        copies_.push_back({dst.handle(), VkBufferCopy{used_, offset, n}});
      }
      used_ += n;
      offset += n;
      bytes -= n;
    }
  }

  // A device-local buffer of `bytes` (rounded up to 4, at least 16, as gpu::uploadBuffer makes them) whose bytes
  // past `bytes` are zero; the caller fills [0, bytes) with write().
  gpu::Buffer create(uint64_t bytes, VkBufferUsageFlags usage) {
    const uint64_t size = std::max<uint64_t>((bytes + 3) & ~uint64_t{3}, 16);
    gpu::Buffer b(device_, size, usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::DeviceLocal);
    write(b, bytes, nullptr, size_t(size - bytes));
    return b;
  }

  // A device-local buffer holding `v` (create + write).
  template <typename T>
  gpu::Buffer upload(const std::vector<T>& v, VkBufferUsageFlags usage) {
    gpu::Buffer b = create(v.size() * sizeof(T), usage);
    write(b, 0, v.data(), v.size() * sizeof(T));
    return b;
  }

  // Flushes and frees the staging buffer (before the texture uploads, which have their own).
  void release() {
    flush();
    staging_.reset();
  }

  // Submits the pending copies and waits for them; the staging buffer is free again afterwards.
  void flush() {
    if (copies_.empty()) return;
    VkCommandBuffer cmd = device_.beginOneShot();
    for (const Copy& c : copies_) vkCmdCopyBuffer(cmd, staging_.handle(), c.dst, 1, &c.region);
    device_.submitOneShot(cmd);  // waits: the staging bytes may be overwritten from here on
    copies_.clear();
    used_ = 0;
  }

 private:
  struct Copy {
    VkBuffer dst;
    VkBufferCopy region;
  };
  gpu::Device& device_;
  gpu::Buffer staging_;
  VkDeviceSize used_ = 0;
  std::vector<Copy> copies_;
};

uint32_t materialFlagsOf(const Material& m) {
  return (m.alphaMode == AlphaMode::Mask ? MATERIAL_FLAG_MASK : 0u) |
         (m.alphaMode == AlphaMode::Blend ? MATERIAL_FLAG_BLEND : 0u) | (m.doubleSided ? MATERIAL_FLAG_DOUBLE_SIDED : 0u) |
         ((materialFeatures(m) & MATERIAL_FEATURE_UNLIT) != 0u ? MATERIAL_FLAG_UNLIT : 0u) |
         ((materialFeatures(m) & MATERIAL_FEATURE_CLEARCOAT) != 0u ? MATERIAL_FLAG_CLEARCOAT : 0u);
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
  d.clearcoat = m.clearcoat;
  d.clearcoatRoughness = m.clearcoatRoughness;
  const auto slots = textureSlots(m);
  for (size_t i = 0; i < kTextureSlotCount; ++i) {
    const TextureRef& t = *slots[i];
    gpu::TextureSlotData& x = d.textures[i];
    x.image = TEXTURE_NONE;
    x.scale = i == TEXTURE_SLOT_NORMAL ? m.normalScale : i == TEXTURE_SLOT_CLEARCOAT_NORMAL ? m.clearcoatNormalScale : 0.0f;
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
      if (tex.sizeClass < scene.textureClasses.size() &&
          scene.textureClasses[tex.sizeClass].format == TextureFormat::Bc5)
        x.samplerBits |= TEXTURE_SAMPLER_TWO_CHANNEL;
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

// The bounds of every cluster of the scene's meshes, in LodData::firstCluster order (scene/clusters.h).
static std::vector<gpu::ClusterData> clusterBounds(const Scene& scene, const std::vector<gpu::MeshData>& meshTable) {
  std::vector<gpu::ClusterData> out;
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    for (size_t l = 0; l < scene.meshes[m].lods.size(); ++l) {
      if (meshTable[m].lods[l].firstCluster == CLUSTER_NONE) continue;
      std::vector<gpu::ClusterData> c = lodClusters(scene.meshes[m], l);
      out.insert(out.end(), c.begin(), c.end());
    }
  return out;
}

Result<GpuScene> uploadScene(gpu::Device& device, const Scene& scene, uint32_t spareObjects) {
  Status valid = validateScene(scene);
  if (!valid) return valid.error();
  GpuScene g;
  if (scene.textureClasses.size() > MAX_TEXTURE_CLASSES)
    return makeError(ErrorCode::CapacityExceeded,
                     fmt::format("the scene has {} texture size classes, over the {} the shading pass binds",
                                 scene.textureClasses.size(), MAX_TEXTURE_CLASSES));
  // The pools are not assembled on the host: the sizes and each mesh's offsets come first, then every mesh's
  // data is streamed to its place through the staging buffer (StagingUploader), so the host holds at most one
  // staging buffer and one mesh's derived data (extras, triangle planes) at a time.
  uint64_t vertexCount = 0, indexCount = 0, extraCount = 0, planeCount = 0;
  std::vector<uint64_t> indexStart;  // each mesh's first index in the index pool
  indexStart.reserve(scene.meshes.size());
  for (const Mesh& mesh : scene.meshes) {
    indexStart.push_back(indexCount);
    gpu::MeshData md{};
    md.boundsSphere = mesh.boundsSphere;
    md.vertexOffset = uint32_t(vertexCount);
    md.vertexCount = uint32_t(mesh.vertices.size());
    md.lodCount = uint32_t(mesh.lods.size());
    md.extraOffset = EXTRA_NONE;
    if (!mesh.tangents.empty() || !mesh.uvs1.empty()) {
      md.extraOffset = uint32_t(extraCount);
      extraCount += mesh.vertices.size();
    }
    for (size_t l = 0; l < mesh.lods.size(); ++l) {
      uint32_t firstCluster = CLUSTER_NONE;
      if (lodHasClusters(mesh.lods[l])) {
        const uint32_t clusters = lodClusterCount(mesh.lods[l]);
        firstCluster = g.clusterCount;
        g.clusterCount += clusters;
        g.maxClustersPerLod = std::max(g.maxClustersPerLod, clusters);
      }
      md.lods[l] = {uint32_t(indexCount) + mesh.lods[l].firstIndex, mesh.lods[l].indexCount, mesh.lods[l].error,
                    firstCluster};
    }
    g.maxTrianglesPerDraw = std::max(g.maxTrianglesPerDraw, mesh.triangleCount(0));
    vertexCount += mesh.vertices.size();
    indexCount += mesh.indices.size();
    // Only lavapipe's micro-raster reads them (sw_raster_cpu.comp); a GPU gets a 16-byte stand-in.
    if (device.isCpu()) planeCount += mesh.indices.size() / 3;
    g.meshTable.push_back(md);
  }
  std::vector<gpu::ObjectData> objects;
  objects.reserve(scene.objects.size());
  for (const Object& o : scene.objects) objects.push_back(packObject(o, scene));
  for (uint32_t i = 0; i < scene.objects.size(); ++i) g.objectMesh.push_back(scene.objects[i].mesh);
  for (uint32_t i = 0; i < spareObjects; ++i) {
    gpu::ObjectData spare{};
    spare.flags = OBJECT_FLAG_HIDDEN | 15u << OBJECT_DRAW_LIST_SHIFT;
    objects.push_back(spare);
    g.objectMesh.push_back(0);
  }
  // Skinned instances: a region of skinned vertices each (position and normal; tangents where the mesh has
  // them) and a mesh slot of their own that keeps the rest mesh's vertices (uv, colour); the skin vertices of
  // each source mesh once.
  uint64_t skinVertexCount = 0, morphDeltaCount = 0;
  std::vector<uint32_t> skinMeshes, morphMeshes;  // source meshes in buffer order
  std::vector<int64_t> skinVertexStart(scene.meshes.size(), -1);
  std::vector<int64_t> morphDeltaStart(scene.meshes.size(), -1);
  for (const SkinnedObject& so : scene.skinnedObjects) {
    const Object& o = scene.objects[so.object];
    const Mesh& mesh = scene.meshes[o.mesh];
    if (skinVertexStart[o.mesh] < 0) {
      skinVertexStart[o.mesh] = int64_t(skinVertexCount);
      skinVertexCount += mesh.skinVertices.size();
      skinMeshes.push_back(o.mesh);
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
        morphDeltaStart[o.mesh] = int64_t(morphDeltaCount);
        morphDeltaCount += mesh.morphDeltas.size();
        morphMeshes.push_back(o.mesh);
      }
      if (morphDeltaCount > UINT32_MAX)
        return makeError(ErrorCode::CapacityExceeded, "more than 2^32-1 morph deltas in the skinned meshes");
      r.morphTargets = mesh.morphTargetCount;
      r.firstMorphDelta = uint32_t(morphDeltaStart[o.mesh]);
    }
    g.meshTable.push_back(g.meshTable[o.mesh]);  // addresses once the buffers exist
    // The clusters' bounds and cones are the rest pose's: a skinned or morphed instance is drawn whole.
    for (gpu::LodData& l : g.meshTable.back().lods) l.firstCluster = CLUSTER_NONE;
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
  if (vertexCount * sizeof(gpu::Vertex) > poolLimit)
    return makeError(ErrorCode::CapacityExceeded,
                     fmt::format("vertex pool needs {:.1f} MiB, over this device's {:.1f} MiB ({} descriptor windows "
                                 "of maxStorageBufferRange, or maxBufferSize)",
                                 vertexCount * sizeof(gpu::Vertex) / 1048576.0, poolLimit / 1048576.0,
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
                             std::pair{"index", indexCount * sizeof(uint32_t)},
                             std::pair{"vertex extras (tangents, TEXCOORD_1)", extraCount * sizeof(gpu::VertexExtra)},
                             std::pair{"object (second window)",
                                       (objects.size() - objectWindowSplit(limit, uint32_t(objects.size()))) *
                                           sizeof(gpu::ObjectData)}}) {
    Status s = check(what, bytes);
    if (!s) return s.error();
  }
  const VkBufferUsageFlags ssbo = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  const VkBufferUsageFlags texel = VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT;
  // One staging buffer for every geometry and table upload: an eighth of the largest buffer to upload, kept
  // between 32 KiB (fewer, larger copies) and 8 MiB (the bound on host memory for any scene). The eighth keeps
  // a small scene's staging well below its own data (and below its pack's largest section, which is the encoded
  // form of that data, down to a quarter of it) at the cost of a few more submissions.
  constexpr uint64_t kStagingBytes = uint64_t{8} << 20, kMinStagingBytes = uint64_t{32} << 10;
  const uint64_t largestUpload = std::max({vertexCount * sizeof(gpu::Vertex), indexCount * sizeof(uint32_t),
                                           extraCount * sizeof(gpu::VertexExtra), planeCount * sizeof(glm::vec4),
                                           skinVertexCount * sizeof(SkinVertex),
                                           morphDeltaCount * sizeof(gpu::MorphDelta),
                                           g.meshTable.size() * sizeof(gpu::MeshData),
                                           objects.size() * sizeof(gpu::ObjectData),
                                           materials.size() * sizeof(gpu::MaterialData)});
  StagingUploader staging(device, std::clamp<uint64_t>((largestUpload / 8 + 15) & ~uint64_t{15}, kMinStagingBytes,
                                                       kStagingBytes));
  uint64_t meshScratch = 0;  // the largest batch buffer (extras, planes) of the upload
  // TRANSFER_SRC: the pools can be read back (tests check the chunked upload byte for byte).
  const VkBufferUsageFlags readBack = VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
  g.vertices = staging.create(vertexCount * sizeof(gpu::Vertex), ssbo | texel | readBack);
  g.indices =
      staging.create(indexCount * sizeof(uint32_t), ssbo | texel | VK_BUFFER_USAGE_INDEX_BUFFER_BIT | readBack);
  // At least 16 bytes: always bindable.
  g.vertexExtras = staging.create(extraCount * sizeof(gpu::VertexExtra), ssbo | readBack);
  g.trianglePlanes = staging.create(planeCount * sizeof(glm::vec4), texel);
  {
    constexpr size_t kBatch = 1024;  // 16-32 KiB of derived records at a time
    uint64_t planeAt = 0;
    std::vector<gpu::VertexExtra> extras;
    std::vector<glm::vec4> planes;  // per triangle (all LODs): object-space unit normal, offset
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
      const Mesh& mesh = scene.meshes[m];
      const gpu::MeshData& md = g.meshTable[m];
      staging.write(g.vertices, uint64_t{md.vertexOffset} * sizeof(gpu::Vertex), mesh.vertices.data(),
               mesh.vertices.size() * sizeof(gpu::Vertex));
      staging.write(g.indices, indexStart[m] * sizeof(uint32_t), mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
      // Extras and planes are derived in batches of kBatch records, so their host buffers stay small.
      if (md.extraOffset != EXTRA_NONE) {
        for (size_t first = 0; first < mesh.vertices.size(); first += kBatch) {
          extras.assign(std::min(kBatch, mesh.vertices.size() - first), gpu::VertexExtra{});
          for (size_t k = 0; k < extras.size(); ++k) {
            const size_t v = first + k;
            gpu::VertexExtra& e = extras[k];
            if (!mesh.tangents.empty() && mesh.tangents[v].w != 0.0f) {
              e.tangent = octEncode(glm::normalize(glm::vec3(mesh.tangents[v])));
              e.tangentW = mesh.tangents[v].w < 0.0f ? -1.0f : 1.0f;
            }
            if (!mesh.uvs1.empty()) {
              e.u1 = mesh.uvs1[v].x;
              e.v1 = mesh.uvs1[v].y;
            }
          }
          staging.write(g.vertexExtras, (uint64_t{md.extraOffset} + first) * sizeof(gpu::VertexExtra), extras.data(),
                        extras.size() * sizeof(gpu::VertexExtra));
          meshScratch = std::max<uint64_t>(meshScratch, extras.capacity() * sizeof(gpu::VertexExtra));
        }
      }
      if (device.isCpu()) {
        const size_t triangles = mesh.indices.size() / 3;
        for (size_t first = 0; first < triangles; first += kBatch) {
          planes.clear();
          for (size_t t = first; t < std::min(triangles, first + kBatch); ++t) {
            const size_t i = 3 * t;
            const glm::dvec3 a(mesh.position(mesh.indices[i])), b(mesh.position(mesh.indices[i + 1])),
                c(mesh.position(mesh.indices[i + 2]));
            const glm::dvec3 n = glm::cross(b - a, c - a);
            const double len = glm::length(n);
            planes.push_back(len > 0.0 ? glm::vec4(glm::vec3(n / len), float(-glm::dot(n / len, a))) : glm::vec4(0.0f));
          }
          staging.write(g.trianglePlanes, planeAt * sizeof(glm::vec4), planes.data(), planes.size() * sizeof(glm::vec4));
          planeAt += planes.size();
          meshScratch = std::max<uint64_t>(meshScratch, planes.capacity() * sizeof(glm::vec4));
        }
      }
    }
  }
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
  g.meshes = staging.upload(g.meshTable, ssbo | texel | VK_BUFFER_USAGE_TRANSFER_SRC_BIT);
  {
    std::vector<gpu::ClusterData> clusters = clusterBounds(scene, g.meshTable);
    if (clusters.empty()) clusters.push_back({});
    g.clusters = staging.upload(clusters, ssbo | VK_BUFFER_USAGE_TRANSFER_SRC_BIT);
  }
  // Device address: frames scatter changed records into it (passes/object_upload_pass.h).
  g.objects = staging.upload(objects, ssbo | texel | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT);
  g.materials = staging.upload(materials, ssbo | texel);
  {
    const VkDeviceSize maxTexels = device.properties().limits.maxTexelBufferElements;
    auto view = [&](const gpu::Buffer& b, VkFormat format, VkDeviceSize texelBytes) {
      const VkDeviceSize range = std::min(b.size() / texelBytes, maxTexels) * texelBytes;
      return gpu::BufferView(device, b, format, 0, std::max(range, texelBytes));
    };
    g.vertexTexels = view(g.vertices, VK_FORMAT_R32G32B32A32_UINT, 16);
    // One texel per triangle (common.glsl triangleIndices), where the device samples RGB32UI texel buffers (an
    // optional format feature); the texel path is off where it does not, and an R32UI view stands in.
    VkFormatProperties rgb{};
    vkGetPhysicalDeviceFormatProperties(device.physicalDevice(), VK_FORMAT_R32G32B32_UINT, &rgb);
    const bool rgbTexels = (rgb.bufferFeatures & VK_FORMAT_FEATURE_UNIFORM_TEXEL_BUFFER_BIT) != 0;
    g.triangleTexels = rgbTexels ? view(g.indices, VK_FORMAT_R32G32B32_UINT, 12) : view(g.indices, VK_FORMAT_R32_UINT, 4);
    g.objectTexels = view(g.objects, VK_FORMAT_R32G32B32A32_UINT, 16);
    g.planeTexels = view(g.trianglePlanes, VK_FORMAT_R32G32B32A32_SFLOAT, 16);
    static_assert(sizeof(gpu::MeshData) == (3 + MAX_LODS) * 16, "common.glsl MESH_TEXELS");
    g.meshTexels = view(g.meshes, VK_FORMAT_R32G32B32A32_UINT, 16);
    static_assert(sizeof(gpu::MaterialData) == (4 + 3 * TEXTURE_SLOTS) * 16, "common.glsl MATERIAL_TEXELS");
    g.materialTexels = view(g.materials, VK_FORMAT_R32G32B32A32_UINT, 16);
    g.texels = rgbTexels;
    for (const gpu::Buffer* b : {&g.vertices, &g.objects, &g.trianglePlanes, &g.meshes, &g.materials})
      g.texels = g.texels && b->size() / 16 <= maxTexels;
    g.texels = g.texels && g.indices.size() / 12 <= maxTexels;  // (the triangle view)
  }
  if (skinVertexCount > 0) {
    g.skinVertices = staging.create(skinVertexCount * sizeof(SkinVertex), ssbo);
    for (uint32_t m : skinMeshes)
      staging.write(g.skinVertices, uint64_t(skinVertexStart[m]) * sizeof(SkinVertex), scene.meshes[m].skinVertices.data(),
               scene.meshes[m].skinVertices.size() * sizeof(SkinVertex));
  }
  if (morphDeltaCount > 0) {
    g.morphDeltas = staging.create(morphDeltaCount * sizeof(gpu::MorphDelta), ssbo);
    for (uint32_t m : morphMeshes)
      staging.write(g.morphDeltas, uint64_t(morphDeltaStart[m]) * sizeof(gpu::MorphDelta),
               scene.meshes[m].morphDeltas.data(), scene.meshes[m].morphDeltas.size() * sizeof(gpu::MorphDelta));
  }
  g.stagingBytes = staging.capacity();
  g.uploadHostBytes = g.stagingBytes + meshScratch + objects.size() * sizeof(gpu::ObjectData) +
                      materials.size() * sizeof(gpu::MaterialData);
  staging.release();  // every geometry buffer is complete before the first frame
  for (const TextureClass& c : scene.textureClasses) {
    TextureUpload uploaded = uploadTextureClass(device, c, {});
    g.textureClasses.push_back(std::move(uploaded.image));
    g.textureBytes += uploaded.gpuBytes;
    g.texturesDecompressed += uploaded.decompressed ? 1u : 0u;
  }
  const uint64_t textureBytes = g.textureBytes;
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
