// The scene's GPU mirror: the unified geometry pool (one vertex and one index storage buffer for every
// mesh and LOD), the mesh table, the object records (64 bytes each) and the materials.
#pragma once

#include <cstdint>
#include <vector>

#include "visbuf/core/result.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

struct GpuScene {
  gpu::Buffer vertices;   // gpu::Vertex[], all meshes
  gpu::Buffer indices;    // uint32[], all meshes and LODs (also bound as the index buffer)
  gpu::Buffer meshes;     // gpu::MeshData[]
  gpu::Buffer objects;    // gpu::ObjectData[]
  gpu::Buffer materials;  // gpu::MaterialData[]
  gpu::Buffer vertexExtras;  // gpu::VertexExtra[] of the meshes with tangents or TEXCOORD_1 (MeshData.extraOffset)
  // The same vertex, index and object records as uniform texel buffers (RGBA32UI; the indices as RGB32UI, one texel
  // per triangle): the hot fetches of the frame read through these where `texels` is set
  // (common.glsl VB_TEXELS), because lavapipe loads a texel as one vector while it reads a storage buffer word by
  // word and lane by lane. Set when every record fits maxTexelBufferElements and the device samples RGB32UI texel
  // buffers; the views cover what fits either way (a descriptor is always written).
  gpu::BufferView vertexTexels, triangleTexels, objectTexels, meshTexels, materialTexels;
  // Per triangle of `indices` (every LOD; triangle k = indices 3k..3k+2): its object-space plane (unit normal,
  // offset; zero for a degenerate one), RGBA32F, for lavapipe's micro-raster back-face test before projection (on
  // a GPU device, whose micro-raster does not test, an empty stand-in).
  gpu::Buffer trianglePlanes;
  gpu::BufferView planeTexels;
  bool texels = false;
  std::vector<gpu::Image> textureClasses;  // Scene::textureClasses, same order: 2D arrays with full mip chains
  uint64_t textureBytes = 0;               // their texel bytes on the GPU
  uint32_t texturesDecompressed = 0;       // BC classes expanded to RGBA8 (device without textureCompressionBC)
  gpu::Image placeholderTexture;           // 1x1x1 white: bound to the class slots the scene does not use
  std::vector<gpu::MeshData> meshTable;  // CPU copy (forward path, ID decoding)
  std::vector<uint32_t> objectMesh;      // meshTable slot each object draws (its own slot when skinned)
  std::vector<uint32_t> objectList;      // draw list of each object (gpu::drawListOf; DRAW_LIST_NONE: BLEND)

  // Skinned instances (Scene::skinnedObjects, same order): each owns a region of one `skinnedVertices` block
  // that the skinning pass rewrites (16-byte SkinnedVertex records, then the skinned tangents where the mesh has
  // tangents) and a mesh table slot (the source mesh's LODs and rest vertices, the region's device addresses,
  // bounds and LOD errors rewritten per pose). Empty for a static scene, and then nothing below is allocated.
  struct SkinnedRegion {
    uint32_t object = 0;
    uint32_t sourceMesh = 0;    // Scene::meshes / meshTable index of the rest-pose mesh
    uint32_t meshSlot = 0;      // meshTable slot of this instance
    uint32_t sourceVertex = 0;  // first rest vertex in the pool
    uint32_t skinVertex = 0;    // first SkinVertex in skinVertices
    uint32_t sourceExtra = EXTRA_NONE;  // first VertexExtra of the rest mesh
    uint32_t vertexCount = 0;
    bool hasTangents = false;   // the mesh has tangents: the region also holds skinned ones
    uint32_t block = 0;         // skinnedVertices[block] holds the region
    uint64_t vertexBytes = 0;   // byte offset of the instance's SkinnedVertex[vertexCount] in that block
    uint64_t tangentBytes = 0;  // byte offset of its uint[vertexCount] skinned tangents; 0: the mesh has none
    uint32_t morphTargets = 0;     // the mesh's morph targets (0: none)
    uint32_t firstMorphDelta = 0;  // its first MorphDelta in morphDeltas
  };
  std::vector<SkinnedRegion> skinned;
  gpu::Buffer skinVertices;     // SkinVertex[] of the meshes skinned objects use (48 bytes each)
  // MorphDelta[] of the meshes skinned objects with morph targets use (36 bytes per vertex and target); null
  // when none has targets.
  gpu::Buffer morphDeltas;
  // The instances' regions (device addresses), 16 (+ 4 with tangents) bytes per vertex, in blocks of at most
  // one buffer's size (maxBufferSize, maxMemoryAllocationSize: 2 GiB on lavapipe, about 89,000 Foxes each).
  std::vector<gpu::Buffer> skinnedVertices;
  uint32_t objectCount = 0;
  // gpu::ClusterData[] of the LOD levels with more than CLUSTER_TRIANGLES triangles (LodData::firstCluster), at least
  // one record (always bindable); clusterCount of them are real, maxClustersPerLod the most one level has.
  gpu::Buffer clusters;
  uint32_t clusterCount = 0;
  uint32_t maxClustersPerLod = 0;
  uint32_t maxTrianglesPerDraw = 0;  // largest LOD0 triangle count: sets the triangle ID bits
  uint64_t bytes = 0;                // GPU memory of the mirror
  // Host memory of the geometry and table upload: its staging buffer (reused, at most 8 MiB) and the transient
  // host buffers besides it (object and material records, one mesh's vertex extras or triangle planes at a
  // time). The Scene's own copy of the geometry and the texture uploads are not included.
  uint64_t stagingBytes = 0;
  uint64_t uploadHostBytes = 0;
};

// The first object of the second descriptor window (SCENE_BINDING_OBJECTS_HIGH): as many objects as one window of
// at most `maxRange` bytes holds, rounded down to a multiple of 4 (so the second window's offset is 256-byte
// aligned, the largest minStorageBufferOffsetAlignment Vulkan allows); `objectCount` when they all fit.
uint32_t objectWindowSplit(uint64_t maxRange, uint32_t objectCount);

// log2 of the vertices per vertex-pool descriptor window (VERTEX_WINDOWS of them): the largest power of two of
// 32-byte vertices one window of at most `maxRange` bytes holds (so window offsets stay 256-byte aligned).
uint32_t vertexWindowShift(uint64_t maxRange);

// Packs an object into its 64-byte record, translation relative to `anchor`.
gpu::ObjectData packObject(const Object& object, const Scene& scene);
// The same for a skinned object: its placement (SkinnedObject::placement) instead of its transform.
gpu::ObjectData packSkinnedObject(const Object& object, const glm::dmat4& placement, const Scene& scene);

// Packs a material into its GPU record: factors, flags, and each texture slot's baked image (class, layer),
// sampler bits and transform (TEXTURE_NONE where the slot has no baked texture).
gpu::MaterialData packMaterial(const Material& material, const Scene& scene);

// The VkFormat a texture class is sampled as: R8G8B8A8 or BC1 RGB / BC3 (UNORM or SRGB by colour space), BC4 /
// BC5 UNORM; `decompressed`: the RGBA8 format a BC class is expanded to on a device without BC formats.
VkFormat textureClassFormat(const TextureClass& textureClass, bool decompressed);

struct TextureUploadOptions {
  bool allowBc = true;                        // false: decompress BC classes even where the device samples them
  // Staging buffer, reused batch after batch; raised to 64 KiB or to one 4-row band of mip 0 when smaller.
  VkDeviceSize stagingBytes = VkDeviceSize{16} << 20;
  VkImageUsageFlags extraUsage = 0;  // beyond SAMPLED | TRANSFER_DST (TRANSFER_SRC: read back by a test)
};
struct TextureUpload {
  gpu::Image image;
  uint64_t gpuBytes = 0;      // texel bytes of the image as created (RGBA8 size where decompressed)
  bool decompressed = false;  // a BC class expanded to RGBA8 (no textureCompressionBC, or !allowBc)
  uint64_t stagingBytes = 0;  // the host staging buffer it went through (freed on return)
};

// Uploads one baked texture class as a sampled 2D array image (textureClassFormat), every layer and mip level,
// left in SHADER_READ_ONLY_OPTIMAL. BC classes stay compressed where the device has textureCompressionBC and are
// decompressed to RGBA8 otherwise. The texels go through one staging buffer of at most options.stagingBytes,
// refilled after each batch's copy has finished, so the upload's host memory stays bounded whatever the class size.
TextureUpload uploadTextureClass(gpu::Device& device, const TextureClass& textureClass,
                                 const TextureUploadOptions& options);
gpu::Image uploadTextureClass(gpu::Device& device, const TextureClass& textureClass);

// Validates and uploads. Fails with CapacityExceeded when a buffer would exceed the device's
// maxStorageBufferRange (128 MiB on lavapipe), naming the buffer and the limit; the object records are read
// through two descriptor windows (objectWindowSplit), so they may take twice that, and the skinned vertices by
// device address from as many buffers as they need (CapacityExceeded only if one instance's region passes
// maxBufferSize / maxMemoryAllocationSize). The geometry pools and tables are written mesh by mesh through one
// reused staging buffer (a quarter of the largest buffer, 64 KiB..8 MiB; a wait between chunks), never assembled
// on the host: stagingBytes / uploadHostBytes report what that cost.
// spareObjects: free object slots after the scene's (hidden records, mesh 0), for objects added later
// (Renderer::addObject); they count in objectCount.
Result<GpuScene> uploadScene(gpu::Device& device, const Scene& scene, uint32_t spareObjects = 0);

}  // namespace visbuf
