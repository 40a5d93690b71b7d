// The scene's GPU mirror: the unified geometry pool (one vertex and one index storage buffer for every
// mesh and LOD), the mesh table, the object records (64 bytes each) and the materials.
#pragma once

#include <cstdint>
#include <vector>

#include "core/result.h"
#include "gpu/resources.h"
#include "scene/scene.h"

namespace visbuf {

struct GpuScene {
  gpu::Buffer vertices;   // gpu::Vertex[], all meshes
  gpu::Buffer indices;    // uint32[], all meshes and LODs (also bound as the index buffer)
  gpu::Buffer meshes;     // gpu::MeshData[]
  gpu::Buffer objects;    // gpu::ObjectData[]
  gpu::Buffer materials;  // gpu::MaterialData[]
  std::vector<gpu::MeshData> meshTable;  // CPU copy (forward path, ID decoding)
  uint32_t objectCount = 0;
  uint32_t maxTrianglesPerDraw = 0;  // largest LOD0 triangle count: sets the triangle ID bits
  uint64_t bytes = 0;                // GPU memory of the mirror
};

// Packs an object into its 64-byte record, translation relative to `anchor`.
gpu::ObjectData packObject(const Object& object, const Scene& scene);

// Validates and uploads. Fails with CapacityExceeded when a buffer would exceed the device's
// maxStorageBufferRange (128 MiB on lavapipe), naming the buffer and the limit.
Result<GpuScene> uploadScene(gpu::Device& device, const Scene& scene);

}  // namespace visbuf
