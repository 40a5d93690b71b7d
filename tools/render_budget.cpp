#include "render_budget.h"

#include <algorithm>

#include <fmt/format.h>
#include <vulkan/vulkan.h>

#include "cli_checks.h"
#include "visbuf/scene/light.h"

namespace visbuf::tools {

namespace {

// Saturating arithmetic: --objects 4294967295 at 16384x16384 must not wrap.
uint64_t add(uint64_t a, uint64_t b) { return a > UINT64_MAX - b ? UINT64_MAX : a + b; }
uint64_t mul(uint64_t a, uint64_t b) { return b != 0 && a > UINT64_MAX / b ? UINT64_MAX : a * b; }

// Per object. Host: the Scene's Object (double-precision transform), uploadScene's packed gpu::ObjectData, the
// host-visible staging copy of it (uploadBuffer), its draw-list and mesh-slot bytes, and a forward-path draw.
constexpr uint64_t kHostPerObject = sizeof(Object) + 2 * sizeof(gpu::ObjectData) + 2 * sizeof(uint32_t) +
                                    sizeof(gpu::DrawCommand) + sizeof(uint32_t);
// Device: the object record, a draw command in each of the two phases (default capacity: one per object),
// the occlusion history word and the two visible-list entries (renderer.cpp: history, visibleList, draws).
constexpr uint64_t kDevicePerObject = sizeof(gpu::ObjectData) + 2 * sizeof(gpu::DrawCommand) + 4 + 2 * 4;
constexpr uint64_t kHostPerLight = sizeof(PointLight) + 2 * sizeof(gpu::PointLightData);
constexpr uint64_t kDevicePerLight = sizeof(gpu::PointLightData);
constexpr uint64_t kHostPerMaterial = sizeof(Material) + 2 * sizeof(gpu::MaterialData);
constexpr uint64_t kDevicePerMaterial = sizeof(gpu::MaterialData);

// Per pixel on the device: the ID (64-bit at most), depth and RGBA16F colour targets per sample, their
// single-sample resolves with MSAA, the colour and ID read-backs, the overdraw target, the micro-raster's
// 64-bit buffer, the depth pyramid (4/3 of a float per pixel), and the G-buffer targets (8 bytes each).
uint64_t devicePerPixel(const RenderBudgetInput& in) {
  uint64_t b = uint64_t(in.msaa) * (8 + 4 + 8);
  if (in.msaa > 1) b += 8 + 4 + 8;
  b += 8 + 8 + 4 + 8 + 6;
  if (in.gbuffer) b += uint64_t(GBUFFER_TARGETS) * 8;
  return b;
}

// Per pixel on the host: the float RGBA colour result, its 8-bit conversion for PNG, the IDs, the reference
// frame's colour and the debug view.
uint64_t hostPerPixel(const RenderBudgetInput& in) {
  uint64_t b = 16 + 4;
  if (in.ids) b += 8;
  if (in.reference) b += 16;
  if (in.debugView) b += 16;
  return b;
}

void part(std::string& detail, const char* what, uint64_t bytes, const std::string& note = {}) {
  if (bytes == 0) return;
  detail += fmt::format("{}{} {}{}", detail.empty() ? "" : ", ", what, formatBytes(bytes),
                        note.empty() ? "" : " (" + note + ")");
}

void addTargets(MemoryEstimate& e, const RenderBudgetInput& in) {
  const uint64_t pixels = uint64_t(in.width) * in.height;
  const uint64_t host = mul(pixels, hostPerPixel(in)), device = mul(pixels, devicePerPixel(in));
  e.host = add(e.host, host);
  e.device = add(e.device, device);
  part(e.hostDetail, "frame read-backs", host, fmt::format("{}x{}, {} bytes a pixel", in.width, in.height,
                                                           hostPerPixel(in)));
  part(e.deviceDetail, "targets", device,
       fmt::format("{}x{}{}, {} bytes a pixel", in.width, in.height,
                   in.msaa > 1 ? fmt::format(" x{} MSAA", in.msaa) : std::string(), devicePerPixel(in)));
}

}  // namespace

MemoryEstimate estimateRender(const RenderBudgetInput& in) {
  MemoryEstimate e;
  const uint64_t oh = mul(in.objects, kHostPerObject), od = mul(in.objects, kDevicePerObject);
  e.host = add(e.host, oh);
  e.device = add(e.device, od);
  part(e.hostDetail, "objects", oh, fmt::format("{} bytes each", kHostPerObject));
  part(e.deviceDetail, "objects", od, fmt::format("{} bytes each", kDevicePerObject));
  const uint64_t lh = mul(in.lights, kHostPerLight), ld = mul(in.lights, kDevicePerLight);
  e.host = add(e.host, lh);
  e.device = add(e.device, ld);
  part(e.hostDetail, "lights", lh);
  part(e.deviceDetail, "lights", ld);
  const uint64_t mh = mul(in.materials, kHostPerMaterial), md = mul(in.materials, kDevicePerMaterial);
  e.host = add(e.host, mh);
  e.device = add(e.device, md);
  part(e.hostDetail, "materials", mh);
  part(e.deviceDetail, "materials", md);
  addTargets(e, in);
  return e;
}

MemoryEstimate estimateUpload(const Scene& scene, const RenderBudgetInput& in) {
  // What uploadScene and Renderer::create allocate from a loaded scene: the geometry pool (vertices, indices
  // of every LOD, one plane per triangle, vertex extras), the skinned instances' own vertex regions, the
  // texture classes, then the per-object, per-light and per-material records as above. The host side is the
  // staging copies plus the CPU-side pools uploadScene builds (each about the size of its device buffer).
  uint64_t geometry = 0, skinned = 0, textures = 0;
  for (const Mesh& m : scene.meshes) {
    geometry = add(geometry, mul(m.vertices.size(), sizeof(gpu::Vertex)));
    geometry = add(geometry, mul(m.indices.size(), sizeof(uint32_t)));
    geometry = add(geometry, mul(m.indices.size() / 3, 16));  // triangle planes
    if (!m.tangents.empty() || !m.uvs1.empty()) geometry = add(geometry, mul(m.vertices.size(), sizeof(gpu::VertexExtra)));
    geometry = add(geometry, mul(m.skinVertices.size(), sizeof(SkinVertex)));
    geometry = add(geometry, mul(m.morphDeltas.size(), sizeof(gpu::MorphDelta)));
  }
  for (const SkinnedObject& so : scene.skinnedObjects) {
    if (so.object >= scene.objects.size() || scene.objects[so.object].mesh >= scene.meshes.size()) continue;
    const Mesh& m = scene.meshes[scene.objects[so.object].mesh];
    skinned = add(skinned, mul(m.vertices.size(), sizeof(gpu::SkinnedVertex) + (m.tangents.empty() ? 0 : 4)));
    skinned = add(skinned, sizeof(gpu::MeshData) + sizeof(gpu::SkinInstance));
  }
  for (const TextureClass& c : scene.textureClasses) textures = add(textures, c.texels.size());
  RenderBudgetInput counts = in;
  counts.objects = scene.objects.size();
  counts.lights = scene.pointLights.size();
  counts.materials = scene.materials.size();
  MemoryEstimate e = estimateRender(counts);
  // The scene's own host memory is spent already: count only what the upload adds.
  const uint64_t sceneObjects = mul(scene.objects.size(), sizeof(Object));
  e.host = e.host > sceneObjects ? e.host - sceneObjects : 0;
  e.device = add(e.device, add(geometry, add(skinned, textures)));
  e.host = add(e.host, add(mul(geometry, 2), textures));
  part(e.deviceDetail, "geometry", geometry);
  part(e.deviceDetail, "skinned instances", skinned);
  part(e.deviceDetail, "textures", textures);
  part(e.hostDetail, "upload staging", add(mul(geometry, 2), textures));
  return e;
}

Status checkMemory(const MemoryEstimate& e, const gpu::Device* device, const std::string& what) {
  std::string hostSource;
  const uint64_t host = availableHostMemory(&hostSource);
  uint64_t deviceHeap = UINT64_MAX;
  bool cpu = false;
  if (device) {
    VkPhysicalDeviceMemoryProperties mp{};
    vkGetPhysicalDeviceMemoryProperties(device->physicalDevice(), &mp);
    uint64_t local = 0, any = 0;
    for (uint32_t i = 0; i < mp.memoryHeapCount; ++i) {
      any = std::max<uint64_t>(any, mp.memoryHeaps[i].size);
      if (mp.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
        local = std::max<uint64_t>(local, mp.memoryHeaps[i].size);
    }
    deviceHeap = local ? local : any;
    cpu = device->isCpu();
  }
  // A CPU device's memory is the host's: both parts come out of it.
  const uint64_t hostNeed = cpu ? add(e.host, e.device) : e.host;
  if (hostNeed > host)
    return makeError(ErrorCode::CapacityExceeded,
                     fmt::format("{} needs an estimated {} of host memory{} ({}{}{}), but this process can allocate "
                                 "about {} ({}); ask for fewer objects or a smaller image",
                                 what, formatBytes(hostNeed), cpu ? " (a CPU device: its memory is the host's)" : "",
                                 e.hostDetail, cpu && !e.deviceDetail.empty() ? "; device: " : "",
                                 cpu ? e.deviceDetail : std::string(), formatBytes(host), hostSource));
  // (A CPU device's heap size is nominal -- lavapipe reports 2 GiB and allocates from the host beyond it --
  // so only the host bound applies to it.)
  if (device && !cpu && e.device > deviceHeap)
    return makeError(ErrorCode::CapacityExceeded,
                     fmt::format("{} needs an estimated {} of device memory ({}), but {}'s largest memory heap holds "
                                 "{}; ask for fewer objects or a smaller image",
                                 what, formatBytes(e.device), e.deviceDetail, device->name(),
                                 formatBytes(deviceHeap)));
  return {};
}

}  // namespace visbuf::tools
