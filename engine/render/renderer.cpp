// The frame script: the only place that knows the pass order and inserts the barriers between them.
//
//   setup ─► cull.comp ─► visibility.{vert,frag} ─► [light_cull.comp] ─► shade.comp ─► readback   (visbuf path;
//                                                      light culling only with point lights)
//                         classified shading: ... ─► classify.comp ─► shade.comp per material ─► readback
//   setup ─► forward.{vert,frag} ─► readback                                      (forward path)
//   both: ─► transparent_pass before the readback, only for scenes with BLEND materials
//   setup ─► cull.comp ─► gbuffer.{vert,frag} ─► gbuffer_lighting.comp ─► readback (G-buffer baseline)
//
// Each pass is recorded into its own command buffer, all submitted at once (Mesa 22.3 lavapipe
// crashed on a dispatch + barrier + timestamps in one command buffer).
#include "visbuf/render/renderer.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <glm/gtc/packing.hpp>

#include "visbuf/gpu/check.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/passes/classify_pass.h"
#include "visbuf/passes/cull_pass.h"
#include "visbuf/passes/depth_pyramid_pass.h"
#include "visbuf/passes/forward_pass.h"
#include "visbuf/passes/gbuffer_lighting_pass.h"
#include "visbuf/passes/gbuffer_pass.h"
#include "visbuf/passes/light_cull_pass.h"
#include "visbuf/passes/shade_pass.h"
#include "visbuf/passes/skin_pass.h"
#include "visbuf/passes/sw_raster_pass.h"
#include "visbuf/passes/transparent_pass.h"
#include "visbuf/render/animation_state.h"
#include "visbuf/passes/visibility_pass.h"
#include "visbuf/render/frame_math.h"
#include "visbuf/scene/gpu_scene.h"

namespace visbuf {

const char* renderPathName(RenderPath path) {
  return path == RenderPath::Visbuf ? "visbuf" : path == RenderPath::GBuffer ? "gbuffer" : "forward";
}
const char* cullModeName(CullMode mode) {
  return mode == CullMode::None ? "none" : mode == CullMode::Frustum ? "frustum" : "occlusion";
}
const char* shadingModeName(ShadingMode mode) {
  return mode == ShadingMode::Auto ? "auto" : mode == ShadingMode::Uber ? "uber" : "classified";
}
ShadingMode parseShadingMode(const std::string& name) {
  return name == "uber" ? ShadingMode::Uber : name == "classified" ? ShadingMode::Classified : ShadingMode::Auto;
}
// The benchmark's verdict per device type (docs/benchmarks.md, "Textured visibility buffer vs G-buffer vs forward,
// and material classification"): the ubershader on both measured so far.
ShadingMode defaultShading(const gpu::Device& device) {
  if (device.isCpu())  // lavapipe: classifying (two passes over the IDs) costs more than the shading saves
    return ShadingMode::Uber;
  return ShadingMode::Uber;  // H100: many small per-material dispatches shade slower than one divergent dispatch
}

const char* swRasterModeName(SwRasterMode mode) {
  return mode == SwRasterMode::Auto ? "auto" : mode == SwRasterMode::On ? "on" : "off";
}
SwRasterMode parseSwRasterMode(const std::string& name) {
  return name == "on" ? SwRasterMode::On : name == "off" ? SwRasterMode::Off : SwRasterMode::Auto;
}
// The micro-raster per device type, as measured (docs/benchmarks.md, "Software micro-raster"): on both. On lavapipe,
// whose hardware-raster geometry path is serial, compute on every core wins wherever it takes anything. On the
// H100 it wins by far on many small objects (1M kittens: 21.4 -> 1.6 ms) but its two full-screen merges cost
// ~0.3 ms a frame, more than the hardware raster of a few thousand small triangles (city 100k: 1.20 -> 1.58 ms):
// there Auto keeps it only while it takes at least kGpuSwMinTriangles (~0.3 ms of hardware raster at ~0.9 Gtri/s).
bool defaultSwRaster(const gpu::Device&) { return true; }
constexpr uint64_t kGpuSwMinTriangles = 262144;

const char* skinBoundsName(SkinBounds bounds) { return bounds == SkinBounds::Gpu ? "gpu" : "joints"; }

std::string IdEncoding::describe() const {
  if (wide) return fmt::format("64-bit rg32ui (x: draw slot + 1, {} bits used; y: triangle, {} bits used)", slotBits, triangleBits);
  return fmt::format("32-bit r32ui (draw slot {} bits | triangle {} bits, +1; 0 = nothing)", slotBits, triangleBits);
}

IdEncoding chooseIdEncoding(uint32_t drawCapacity, uint32_t maxTrianglesPerDraw, bool forceWide) {
  IdEncoding e;
  auto bitsFor = [](uint64_t n) { return n <= 1 ? 1u : uint32_t(std::bit_width(n - 1)); };
  e.triangleBits = bitsFor(maxTrianglesPerDraw);
  e.slotBits = bitsFor(drawCapacity);
  // Narrow only if the largest encoded value, ((cap-1) << triBits | (2^triBits - 1)) + 1, fits in 32 bits.
  const uint64_t largest = ((uint64_t(drawCapacity) - 1) << e.triangleBits | ((1ull << e.triangleBits) - 1)) + 1;
  e.wide = forceWide || e.slotBits + e.triangleBits > 32 || largest > 0xFFFFFFFFull;
  return e;
}

std::vector<uint32_t> supportedMsaaSamples(gpu::Device& device) {
  const VkPhysicalDeviceLimits& l = device.properties().limits;
  VkSampleCountFlags counts = l.framebufferColorSampleCounts & l.framebufferDepthSampleCounts &
                              l.sampledImageIntegerSampleCounts & l.sampledImageDepthSampleCounts;
  // And each target format with its usage (integer colour attachments included: the limits are minimums, a
  // format may report fewer).
  const struct {
    VkFormat format;
    VkImageUsageFlags usage;
  } targets[] = {{VK_FORMAT_R32_UINT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT},
                 {VK_FORMAT_R32G32_UINT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT},
                 {VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT},
                 {VK_FORMAT_R16G16B16A16_SFLOAT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT}};
  for (const auto& t : targets) {
    VkImageFormatProperties fp{};
    if (vkGetPhysicalDeviceImageFormatProperties(device.physicalDevice(), t.format, VK_IMAGE_TYPE_2D,
                                                 VK_IMAGE_TILING_OPTIMAL, t.usage, 0, &fp) != VK_SUCCESS)
      counts = 0;
    counts &= fp.sampleCounts;
  }
  std::vector<uint32_t> out{1};
  for (uint32_t n : {2u, 4u})
    if ((counts & n) && l.standardSampleLocations) out.push_back(n);
  return out;
}

namespace {

constexpr VkClearColorValue kBackground{{0.10f, 0.12f, 0.15f, 1.0f}};
constexpr uint32_t kCommandBuffers = 14;  // at most 14: setup, skin, 2 x (cull, raster, micro-raster), pyramid,
                                          // light cull, classify, shade (or G-buffer lighting), transparent, readback
// A pyramid that occluded nothing is skipped for this many frames, then built again to re-probe.
constexpr uint32_t kPyramidProbeInterval = 16;
// Likewise the micro-raster, after a frame in which it took no draw.
constexpr uint32_t kSwProbeInterval = 16;

}  // namespace

// The vertex pool's descriptor windows: window k covers vertices [k << shift, (k + 1) << shift); windows past
// the end of the pool repeat window 0 (bound, never read).
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

struct Renderer::Impl {
  gpu::Device& device;
  const Scene& scene;
  RendererConfig config;
  GpuScene gpuScene;
  IdEncoding encoding;
  uint32_t capacity = 0;      // draws per phase (all draw lists together): draws[0, capacity) early, then late
  // Draw lists (config.h DRAW_LIST_*): list l holds slots [listFirst[l], + listCapacity[l]) of each phase's region;
  // capacity 0 for a list no object of the scene is in. Mirrored in drawLists (BINDING_DRAW_LISTS).
  std::array<uint32_t, DRAW_LISTS> listFirst{}, listCapacity{};
  uint32_t listMask = 0;                 // bit l: listCapacity[l] > 0
  uint32_t swListMask = 0;               // bit l: the micro-raster may take list l's draws (opaque, uncapped)
  std::vector<uint32_t> blendObjects;    // objects with BLEND materials (the transparency pass), scene order
  gpu::Buffer drawLists;
  uint32_t objectSplit = 0;  // first object of the second descriptor window (objectWindowSplit)
  uint32_t vertexShift = 0;  // vertices per vertex-pool window: 1 << vertexShift (vertexWindowShift)

  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
  VkPipelineLayout pipelineLayout = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VkDescriptorSet set = VK_NULL_HANDLE;
  VkSampler sampler = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  std::array<VkCommandBuffer, kCommandBuffers> cmds{};

  passes::CullPass cull;
  passes::VisibilityPass visibility;
  passes::ShadePass shade;
  passes::ClassifyPass classify;  // created by the first classified frame
  passes::ForwardPass forward;
  passes::TransparentPass transparent;  // created only when blendObjects is not empty
  passes::DepthPyramidPass pyramid;
  passes::GBufferPass gbuffer;                   // G-buffer baseline raster
  passes::GBufferLightingPass gbufferLighting;  // and its lighting
  std::array<gpu::Image, GBUFFER_TARGETS> gbufferTargets;  // created by the first G-buffer frame after a resize
  gpu::Specialization textured;  // specialisation of every frame pipeline (windows, texture classes)
  std::unique_ptr<AnimationState> animation;  // skinned scenes only
  passes::SkinPass skin;
  // Software micro-raster (FrameOptions::swRaster): its pipelines (created with the renderer when some list can
  // use it) and its 64-bit per-pixel buffer (created by the first frame that uses it, dropped by a resize).
  passes::SwRasterPass swRaster;
  bool swOn = false;           // this frame routes small objects to it (set in render())
  bool lastSwOn = false;       // the last unfrozen frame did (a frozen frame redraws that frame's draw lists)
  uint32_t swSkipFrames = 0;   // frames left before it is probed again after a frame in which it took nothing
  // Point lights (scenes with any): anchor-relative records and the tile lists. Empty otherwise.
  gpu::Buffer pointLights;
  passes::LightCullPass lightCull;
  bool hasPointLights() const { return !scene.pointLights.empty(); }
  gpu::Buffer history;      // uint per object: visible at the end of the last occlusion-culled frame
  gpu::Buffer visibleList;  // the same set listed (config.h BINDING_VISIBLE_LIST): the early cull's threads
  bool historyDirty = true; // cleared before the next frame (creation, clearHistory)
  bool haveDraws = false;   // a visbuf frame has filled the draw lists (freezeCulling can reuse them)
  CullMode lastCull = CullMode::Frustum;
  gpu::Buffer pyramidReadback;
  gpu::Buffer overdrawReadback;
  gpu::Buffer attributes;           // float[ATTRIBUTE_FLOATS] per pixel; a 64-byte placeholder until asked for
  gpu::Buffer attributesReadback;
  uint32_t pyramidSkipFrames = 0;  // frames left before the pyramid is probed again
  bool usePyramid = true;          // this frame builds the pyramid (set in render())

  gpu::Buffer frameBuffer;  // FrameData, host visible
  gpu::Buffer draws;        // DrawCommand[capacity]
  gpu::BufferView drawTexels;  // the same as R32UI (BINDING_DRAW_TEXELS): the shading's per-pixel fetch
  gpu::Buffer stats;        // uint[STAT_COUNT]
  gpu::Buffer statsReadback;
  gpu::Image ids, depth, color;
  // MSAA (FrameOptions::msaa > 1): multisampled IDs and depth (visbuf, forward shares the depth) and forward
  // colour, created by the first frame at a count (msaaSamples) and dropped by a resize; the single-sample ids and
  // depth above stay allocated (the descriptor set's stand-ins). Pipelines for that count likewise.
  uint32_t msaaSamples = 0;  // sample count of idsMs / depthMs (0: none)
  gpu::Image idsMs, depthMs, colorMs;
  passes::VisibilityPass visibilityMs;
  passes::ForwardPass forwardMs;
  uint32_t visibilityMsSamples = 0, forwardMsSamples = 0;
  bool descriptorsMsaa = false;  // BINDING_VISIBILITY / BINDING_LIGHT_DEPTH hold the multisampled views
  std::vector<uint32_t> msaaCounts;  // supportedMsaaSamples(device)
  gpu::Image overdraw;    // r32ui, GENERAL: raster writes per pixel (countOverdraw)
  gpu::Image forwardIds;  // forward path with readIds only (rg32ui: object + 1, triangle); lazily created
  gpu::Buffer colorReadback, idsReadback, drawsReadback;
  std::unique_ptr<gpu::TimestampPool> timestamps;

  Impl(gpu::Device& d, const Scene& s) : device(d), scene(s) {}
  ~Impl() {
    VkDevice dev = device.device();
    vkDeviceWaitIdle(dev);
    vkFreeCommandBuffers(dev, device.commandPool(), kCommandBuffers, cmds.data());
    vkDestroyFence(dev, fence, nullptr);
    vkDestroySampler(dev, sampler, nullptr);
    vkDestroyDescriptorPool(dev, pool, nullptr);
    vkDestroyPipelineLayout(dev, pipelineLayout, nullptr);
    vkDestroyDescriptorSetLayout(dev, setLayout, nullptr);
  }

  void createLayouts() {
    VkDevice dev = device.device();
    const VkShaderStageFlags all = VK_SHADER_STAGE_COMPUTE_BIT | VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    std::vector<VkDescriptorSetLayoutBinding> b = {
        {BINDING_FRAME, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, all, nullptr},
        {BINDING_OBJECTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_MESHES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_VERTICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_INDICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_DRAWS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_STATS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_MATERIALS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_VISIBILITY, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_COLOR, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_PYRAMID, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_HISTORY, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_VISIBLE_LIST, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_OVERDRAW, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_FRAGMENT_BIT, nullptr},
        {BINDING_ATTRIBUTES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_OBJECTS_HIGH, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_VERTICES_1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_VERTICES_2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_VERTICES_3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_TEXTURE_CLASSES, VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE, MAX_TEXTURE_CLASSES, all, nullptr},
        {BINDING_VERTEX_EXTRAS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_DRAW_LISTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_SW_VISIBILITY, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_GBUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, GBUFFER_TARGETS, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_GBUFFER_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_LIGHTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_LIGHT_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {BINDING_LIGHT_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_MATERIAL_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_TILE_LIST, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_VERTEX_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, all, nullptr},
        {BINDING_INDEX_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, all, nullptr},
        {BINDING_OBJECT_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, all, nullptr},
        {BINDING_TRIANGLE_PLANES, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {BINDING_MESH_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, all, nullptr},
        {BINDING_MATERIAL_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, all, nullptr},
        {BINDING_DRAW_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
    };
    VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    lci.bindingCount = uint32_t(b.size());
    lci.pBindings = b.data();
    VK_CHECK(vkCreateDescriptorSetLayout(dev, &lci, nullptr, &setLayout));
    VkPipelineLayoutCreateInfo pci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pci.setLayoutCount = 1;
    pci.pSetLayouts = &setLayout;
    VkPushConstantRange range{gpu::kPassConstantStages, 0, sizeof(gpu::PassConstants)};
    pci.pushConstantRangeCount = 1;
    pci.pPushConstantRanges = &range;
    VK_CHECK(vkCreatePipelineLayout(dev, &pci, nullptr, &pipelineLayout));
    VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
                                    {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 17 + 2 /*lights*/ + 2 /*classification*/},
                                    {VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE, MAX_TEXTURE_CLASSES},
                                    {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 2 + GBUFFER_TARGETS + 1 + 1 /*light depth*/},
                                    {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 2},
                                    {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 7}};
    VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dpci.maxSets = 1;
    dpci.poolSizeCount = uint32_t(std::size(sizes));
    dpci.pPoolSizes = sizes;
    VK_CHECK(vkCreateDescriptorPool(dev, &dpci, nullptr, &pool));
    VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    ai.descriptorPool = pool;
    ai.descriptorSetCount = 1;
    ai.pSetLayouts = &setLayout;
    VK_CHECK(vkAllocateDescriptorSets(dev, &ai, &set));
    VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    sci.magFilter = sci.minFilter = VK_FILTER_NEAREST;
    sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    sci.maxLod = VK_LOD_CLAMP_NONE;
    VK_CHECK(vkCreateSampler(dev, &sci, nullptr, &sampler));
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VK_CHECK(vkCreateFence(dev, &fci, nullptr, &fence));
    VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cai.commandPool = device.commandPool();
    cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cai.commandBufferCount = kCommandBuffers;
    VK_CHECK(vkAllocateCommandBuffers(dev, &cai, cmds.data()));
  }

  void createTargets(uint32_t width, uint32_t height) {
    vkDeviceWaitIdle(device.device());
    const VkFormat idFormat = encoding.wide ? VK_FORMAT_R32G32_UINT : VK_FORMAT_R32_UINT;
    ids = gpu::Image(device, idFormat, width, height,
                     VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                     VK_IMAGE_ASPECT_COLOR_BIT);
    depth = gpu::Image(device, VK_FORMAT_D32_SFLOAT, width, height,
                       VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_DEPTH_BIT);
    pyramid.resize(depth);
    color = gpu::Image(device, VK_FORMAT_R16G16B16A16_SFLOAT, width, height,
                       VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT |
                           VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                       VK_IMAGE_ASPECT_COLOR_BIT);
    const VkDeviceSize pixels = VkDeviceSize(width) * height;
    colorReadback = gpu::Buffer(device, pixels * 8, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
    forwardIds.reset();
    idsMs.reset();
    depthMs.reset();
    colorMs.reset();
    msaaSamples = 0;
    descriptorsMsaa = false;
    for (gpu::Image& t : gbufferTargets) t.reset();
    overdrawReadback.reset();
    resizeAttributes(ATTRIBUTE_FLOATS * sizeof(float));
    overdraw = gpu::Image(device, VK_FORMAT_R32_UINT, width, height,
                          VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                          VK_IMAGE_ASPECT_COLOR_BIT);
    {
      VkCommandBuffer one = device.beginOneShot();
      gpu::imageBarrier(one, overdraw, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                        VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0);
      device.submitOneShot(one);
    }
    idsReadback = gpu::Buffer(device, pixels * 8 /* rg32ui: either path */, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                              gpu::MemoryUse::HostVisible);
    swRaster.resetBuffer(device);
    if (hasPointLights()) lightCull.resize(device, width, height);
    if (classify.created()) classify.resize(device, width, height);
    config.width = width;
    config.height = height;
    writeDescriptors();
  }

  // An empty visible list (no thread in the next early cull) with its dispatch arguments (0, 1, 1).
  // Byte offset of the late cull's refinement list in the visibleList buffer (config.h BINDING_VISIBLE_LIST).
  VkDeviceSize refineListOffset() const { return (VISIBLE_LIST_HEADER + VkDeviceSize(gpuScene.objectCount)) * 4; }
  // Empties the visible list and the refinement list (count 0, dispatch size 0 x 1 x 1).
  void resetVisibleList(VkCommandBuffer cmd) const {
    const uint32_t header[VISIBLE_LIST_HEADER] = {0, 0, 1, 1};
    vkCmdUpdateBuffer(cmd, visibleList.handle(), 0, sizeof(header), header);
    vkCmdUpdateBuffer(cmd, visibleList.handle(), refineListOffset(), sizeof(header), header);
  }

  // The attribute buffer is only as large as asked for (a full-screen one is 64 bytes per pixel).
  void resizeAttributes(VkDeviceSize bytes) {
    attributes = gpu::Buffer(device, bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                                VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                             gpu::MemoryUse::DeviceLocal);
    attributesReadback.reset();
  }

  void writeDescriptors() {
    // Objects: two windows of one buffer, split where one descriptor range would end (objectWindowSplit).
    const VkDeviceSize lowBytes = VkDeviceSize(objectSplit) * sizeof(gpu::ObjectData);
    const bool highUsed = objectSplit < gpuScene.objectCount;
    const std::array<VkDescriptorBufferInfo, VERTEX_WINDOWS> vw = vertexWindows(gpuScene.vertices, vertexShift);
    VkDescriptorBufferInfo bufs[17] = {
        {frameBuffer.handle(), 0, VK_WHOLE_SIZE},
        {gpuScene.objects.handle(), 0, highUsed ? lowBytes : VK_WHOLE_SIZE},
        {gpuScene.meshes.handle(), 0, VK_WHOLE_SIZE},    vw[0],
        {gpuScene.indices.handle(), 0, VK_WHOLE_SIZE},   {draws.handle(), 0, VK_WHOLE_SIZE},
        {stats.handle(), 0, VK_WHOLE_SIZE},              {gpuScene.materials.handle(), 0, VK_WHOLE_SIZE},
        {history.handle(), 0, VK_WHOLE_SIZE},            {attributes.handle(), 0, VK_WHOLE_SIZE},
        {gpuScene.objects.handle(), highUsed ? lowBytes : 0, VK_WHOLE_SIZE},
        vw[1], vw[2], vw[3], {drawLists.handle(), 0, VK_WHOLE_SIZE}, {swRaster.buffer.handle(), 0, VK_WHOLE_SIZE},
        {visibleList.handle(), 0, VK_WHOLE_SIZE}};
    const uint32_t bufBindings[17] = {BINDING_FRAME,      BINDING_OBJECTS,      BINDING_MESHES,     BINDING_VERTICES,
                                      BINDING_INDICES,    BINDING_DRAWS,        BINDING_STATS,      BINDING_MATERIALS,
                                      BINDING_HISTORY,    BINDING_ATTRIBUTES,   BINDING_OBJECTS_HIGH,
                                      BINDING_VERTICES_1, BINDING_VERTICES_2,   BINDING_VERTICES_3,
                                      BINDING_DRAW_LISTS, BINDING_SW_VISIBILITY, BINDING_VISIBLE_LIST};
    std::vector<VkWriteDescriptorSet> w;
    for (int i = 0; i < 17; ++i) {
      VkWriteDescriptorSet x{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      x.dstSet = set;
      x.dstBinding = bufBindings[i];
      x.descriptorCount = 1;
      x.descriptorType = i == 0 ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      x.pBufferInfo = &bufs[i];
      w.push_back(x);
    }
    // MSAA frames: the shading pass and the light culling read the multisampled targets (only those variants
    // declare multisampled images; every other shader ignores these bindings).
    VkDescriptorImageInfo idInfo{sampler, (descriptorsMsaa ? idsMs : ids).view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    VkDescriptorImageInfo colorInfo{VK_NULL_HANDLE, color.view(), VK_IMAGE_LAYOUT_GENERAL};
    VkWriteDescriptorSet x{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    x.dstSet = set;
    x.descriptorCount = 1;
    x.dstBinding = BINDING_VISIBILITY;
    x.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    x.pImageInfo = &idInfo;
    w.push_back(x);
    x.dstBinding = BINDING_COLOR;
    x.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    x.pImageInfo = &colorInfo;
    w.push_back(x);
    VkDescriptorImageInfo overdrawInfo{VK_NULL_HANDLE, overdraw.view(), VK_IMAGE_LAYOUT_GENERAL};
    x.dstBinding = BINDING_OVERDRAW;
    x.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    x.pImageInfo = &overdrawInfo;
    w.push_back(x);
    VkDescriptorImageInfo pyramidInfo{sampler, pyramid.pyramid().view(), VK_IMAGE_LAYOUT_GENERAL};
    x.dstBinding = BINDING_PYRAMID;
    x.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    x.pImageInfo = &pyramidInfo;
    w.push_back(x);
    // Texture classes: the scene's, then the placeholder in every unused slot (material.glsl); vertex extras.
    std::array<VkDescriptorImageInfo, MAX_TEXTURE_CLASSES> textureInfos;
    for (size_t i = 0; i < textureInfos.size(); ++i) {
      const gpu::Image& t = i < gpuScene.textureClasses.size() ? gpuScene.textureClasses[i] : gpuScene.placeholderTexture;
      textureInfos[i] = {VK_NULL_HANDLE, t.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    }
    x.dstBinding = BINDING_TEXTURE_CLASSES;
    x.descriptorType = VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE;
    x.descriptorCount = MAX_TEXTURE_CLASSES;
    x.pImageInfo = textureInfos.data();
    w.push_back(x);
    const VkBufferView texelViews[7] = {gpuScene.vertexTexels.handle(), gpuScene.indexTexels.handle(),
                                        gpuScene.objectTexels.handle(), gpuScene.planeTexels.handle(),
                                        gpuScene.meshTexels.handle(),   gpuScene.materialTexels.handle(),
                                        drawTexels.handle()};
    const uint32_t texelBindings[7] = {BINDING_VERTEX_TEXELS,   BINDING_INDEX_TEXELS, BINDING_OBJECT_TEXELS,
                                       BINDING_TRIANGLE_PLANES, BINDING_MESH_TEXELS,  BINDING_MATERIAL_TEXELS,
                                       BINDING_DRAW_TEXELS};
    for (int i = 0; i < 7; ++i) {
      VkWriteDescriptorSet t{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      t.dstSet = set;
      t.dstBinding = texelBindings[i];
      t.descriptorCount = 1;
      t.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
      t.pTexelBufferView = &texelViews[i];
      w.push_back(t);
    }
    VkDescriptorBufferInfo extrasInfo{gpuScene.vertexExtras.handle(), 0, VK_WHOLE_SIZE};
    x.dstBinding = BINDING_VERTEX_EXTRAS;
    x.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    x.descriptorCount = 1;
    x.pImageInfo = nullptr;
    x.pBufferInfo = &extrasInfo;
    w.push_back(x);
    x.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    x.pBufferInfo = nullptr;
    // G-buffer targets: until a G-buffer frame creates them, the depth stands in (lavapipe reads every descriptor
    // of a bound set, so none may stay unwritten; only gbuffer_lighting.comp samples these).
    VkDescriptorImageInfo gbufferDepthInfo{sampler, depth.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    std::array<VkDescriptorImageInfo, GBUFFER_TARGETS> gbufferInfo{};
    for (uint32_t i = 0; i < GBUFFER_TARGETS; ++i)
      gbufferInfo[i] = gbufferTargets[i] ? VkDescriptorImageInfo{sampler, gbufferTargets[i].view(),
                                                                 VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL}
                                         : gbufferDepthInfo;
    x.dstBinding = BINDING_GBUFFER;
    x.descriptorCount = GBUFFER_TARGETS;
    x.pImageInfo = gbufferInfo.data();
    w.push_back(x);
    x.dstBinding = BINDING_GBUFFER_DEPTH;
    x.descriptorCount = 1;
    x.pImageInfo = &gbufferDepthInfo;
    w.push_back(x);
    // Lights: with no point lights nothing is allocated; the shaders never read these bindings then
    // (FrameData.pointLightCount = 0), which alias the stats buffer only to keep the set complete.
    VkDescriptorBufferInfo lightInfo = hasPointLights() ? VkDescriptorBufferInfo{pointLights.handle(), 0, VK_WHOLE_SIZE}
                                                        : VkDescriptorBufferInfo{stats.handle(), 0, VK_WHOLE_SIZE};
    VkDescriptorBufferInfo tileInfo = hasPointLights() ? VkDescriptorBufferInfo{lightCull.tiles().handle(), 0, VK_WHOLE_SIZE}
                                                       : VkDescriptorBufferInfo{stats.handle(), 0, VK_WHOLE_SIZE};
    VkDescriptorImageInfo lightDepthInfo{sampler, (descriptorsMsaa ? depthMs : depth).view(),
                                         VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    x.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    x.pImageInfo = nullptr;
    x.dstBinding = BINDING_LIGHTS;
    x.pBufferInfo = &lightInfo;
    w.push_back(x);
    x.dstBinding = BINDING_LIGHT_TILES;
    x.pBufferInfo = &tileInfo;
    w.push_back(x);
    x.dstBinding = BINDING_LIGHT_DEPTH;
    x.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    x.pBufferInfo = nullptr;
    x.pImageInfo = &lightDepthInfo;
    w.push_back(x);
    // Classification: until a classified frame creates its buffers, the stats buffer stands in (never read).
    VkDescriptorBufferInfo classifyInfo[2] = {{stats.handle(), 0, VK_WHOLE_SIZE}, {stats.handle(), 0, VK_WHOLE_SIZE}};
    if (classify.created())
      classifyInfo[0].buffer = classify.materialTiles().handle(), classifyInfo[1].buffer = classify.tileList().handle();
    x.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    x.pImageInfo = nullptr;
    x.dstBinding = BINDING_MATERIAL_TILES;
    x.pBufferInfo = &classifyInfo[0];
    w.push_back(x);
    x.dstBinding = BINDING_TILE_LIST;
    x.pBufferInfo = &classifyInfo[1];
    w.push_back(x);
    vkUpdateDescriptorSets(device.device(), uint32_t(w.size()), w.data(), 0, nullptr);
  }

  // The G-buffer pipelines and targets at the current size (only renderers that draw the G-buffer baseline pay
  // for them).
  void ensureGBufferTargets() {
    if (gbuffer.formats.color[0] == VK_FORMAT_UNDEFINED) {  // not created yet
      gbuffer = passes::GBufferPass::create(device, pipelineLayout, textured, listMask);
      gbufferLighting = passes::GBufferLightingPass::create(device, pipelineLayout, textured.windowed);
    }
    if (gbufferTargets[0]) return;
    for (uint32_t i = 0; i < GBUFFER_TARGETS; ++i)
      gbufferTargets[i] = gpu::Image(device, gbuffer.formats.color[i], config.width, config.height,
                                     VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                                     VK_IMAGE_ASPECT_COLOR_BIT);
    writeDescriptors();
  }

  // FrameOptions::msaa against the device and the frame's other options (what MSAA does not cover is refused).
  Status checkMsaa(const FrameOptions& o) const {
    if (o.msaa == 1) return {};
    if (o.msaa != 2 && o.msaa != 4)
      return makeError(ErrorCode::InvalidArgument, fmt::format("msaa {}: the sample count must be 1, 2 or 4", o.msaa));
    if (std::find(msaaCounts.begin(), msaaCounts.end(), o.msaa) == msaaCounts.end())
      return makeError(ErrorCode::Unsupported,
                       fmt::format("msaa {} is not supported by {}: supported sample counts (for the r32ui/rg32ui ID, "
                                   "D32 depth and rgba16f colour targets) are {}",
                                   o.msaa, device.name(), fmt::join(msaaCounts, ", ")));
    const char* refused = o.path == RenderPath::GBuffer ? "the G-buffer path"
                          : !blendObjects.empty()       ? "scenes with BLEND materials (the transparency pass)"
                          : o.countOverdraw             ? "the overdraw count (countOverdraw, --view overdraw)"
                          : o.readAttributes            ? "the attribute readback (readAttributes)"
                          : o.readIds && o.path == RenderPath::Forward ? "the forward path's ID target (readIds)"
                                                                        : nullptr;
    if (refused)
      return makeError(ErrorCode::Unsupported,
                       fmt::format("msaa {}: {} is single-sampled only; use msaa 1", o.msaa, refused));
    return {};
  }

  // The multisampled targets and pipelines of this frame's sample count (created once per count and size), and
  // the descriptors that the shading and light culling passes read them through.
  void prepareMsaa(const FrameOptions& options) {
    const bool msaa = options.msaa > 1;
    const auto samples = VkSampleCountFlagBits(options.msaa);
    if (msaa && msaaSamples != options.msaa) {
      idsMs = gpu::Image(device, ids.format(), config.width, config.height,
                         VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_COLOR_BIT, 1,
                         0, samples);
      depthMs = gpu::Image(device, VK_FORMAT_D32_SFLOAT, config.width, config.height,
                           VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                           VK_IMAGE_ASPECT_DEPTH_BIT, 1, 0, samples);
      colorMs.reset();
      pyramid.resize(depth, &depthMs);  // level 0 from either depth
      msaaSamples = options.msaa;
      descriptorsMsaa = !msaa;  // the pyramid and the ID views changed: rewrite below
    }
    if (msaa && options.path == RenderPath::Visbuf) {
      if (visibilityMsSamples != options.msaa)
        visibilityMs = passes::VisibilityPass::create(device, pipelineLayout, textured, listMask, samples);
      visibilityMsSamples = options.msaa;
      shade.createMsaa(device, pipelineLayout, textured);
    }
    if (msaa && options.path == RenderPath::Forward) {
      if (forwardMsSamples != options.msaa)
        forwardMs = passes::ForwardPass::create(device, pipelineLayout, textured, listMask, samples);
      forwardMsSamples = options.msaa;
      if (!colorMs)
        colorMs = gpu::Image(device, VK_FORMAT_R16G16B16A16_SFLOAT, config.width, config.height,
                             VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, VK_IMAGE_ASPECT_COLOR_BIT, 1, 0, samples);
    }
    if (descriptorsMsaa != msaa) {
      descriptorsMsaa = msaa;
      writeDescriptors();
    }
  }

  // The classification pipelines and buffers (only renderers that shade classified frames pay for them).
  void ensureClassify() {
    if (classify.created()) return;
    std::vector<bool> sampling;  // per material: samples a texture
    for (const Material& m : scene.materials) sampling.push_back(packMaterial(m, scene).slotCount > 0);
    classify.create(device, pipelineLayout, textured, std::move(sampling));
    classify.resize(device, config.width, config.height);
    writeDescriptors();
  }
  // The shading mode of a visbuf frame (Auto resolved; the attribute record and MSAA exist in the ubershader only).
  ShadingMode shadingFor(const FrameOptions& options) const {
    if (options.path != RenderPath::Visbuf || options.readAttributes || options.msaa > 1) return ShadingMode::Uber;
    return options.shading == ShadingMode::Auto ? defaultShading(device) : options.shading;
  }

  void beginCmd(VkCommandBuffer cmd) {
    VK_CHECK(vkResetCommandBuffer(cmd, 0));
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VK_CHECK(vkBeginCommandBuffer(cmd, &bi));
  }

  void copyImageToBuffer(VkCommandBuffer cmd, const gpu::Image& image, const gpu::Buffer& buffer) {
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {image.width(), image.height(), 1};
    vkCmdCopyImageToBuffer(cmd, image.handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer.handle(), 1, &region);
  }

  gpu::FrameData frameData(const Camera& camera, const FrameMath& math, const FrameOptions& options) const {
    gpu::FrameData f{};
    f.viewProj = glm::mat4(math.viewProj);
    f.view = glm::mat4(math.view);
    f.projX = float(math.proj[0][0]);
    f.projY = float(math.proj[1][1]);
    f.pyramidLevels = usePyramid ? pyramid.levels() : 0;
    f.cameraOffset = glm::vec4(glm::vec3(scene.anchor - camera.position), 0.0f);
    for (int i = 0; i < 5; ++i) f.frustum[i] = glm::vec4(math.planes[size_t(i)]);
    f.lightDir = glm::vec4(glm::normalize(scene.lightDirection), scene.lightIntensity);
    f.pointLightCount = uint32_t(scene.pointLights.size());
    f.lightTilesX = cullLights(options) ? lightCull.tilesX() : 0u;
    f.viewport = glm::vec4(float(config.width), float(config.height), 1.0f / config.width, 1.0f / config.height);
    f.lodScale = float(math.lodScale);
    f.lodErrorPixels = options.lodErrorPixels;
    f.nearPlane = float(camera.nearPlane);
    f.objectCount = gpuScene.objectCount;
    f.drawCapacity = capacity;
    f.cullMode = options.cull == CullMode::None      ? CULL_NONE
                 : options.cull == CullMode::Frustum ? CULL_FRUSTUM
                                                     : CULL_OCCLUSION;
    f.triangleBits = encoding.triangleBits;
    f.wideIds = encoding.wide ? 1u : 0u;
    f.objectSplit = objectSplit;
    f.vertexWindowShift = vertexShift;
    f.msaaSamples = options.msaa;
    f.swRaster = swOn ? 1u : 0u;
    f.swMaxPixels = options.swRasterPixels;
    f.swTriangleBits = encoding.wide ? 32u - std::min(encoding.slotBits, 31u) : encoding.triangleBits;
    f.swMaxTriangles = encoding.wide ? std::min(1u << f.swTriangleBits, SW_RASTER_MAX_TRIANGLES) : SW_RASTER_MAX_TRIANGLES;
    return f;
  }

  // This frame routes small objects to the software micro-raster: asked for, the visbuf path, single-sampled, no
  // overdraw count (it counts hardware raster writes), a list it may take, and its buffer within one range.
  bool swActive(const FrameOptions& options) const {
    const bool asked = options.swRaster == SwRasterMode::Auto ? defaultSwRaster(device) : options.swRaster == SwRasterMode::On;
    return asked && options.path == RenderPath::Visbuf && options.msaa == 1 && !options.countOverdraw &&
           swListMask != 0 &&
           VkDeviceSize(config.width) * config.height * 8 <= device.properties().limits.maxStorageBufferRange;
  }
  // Draws of list l in a phase that went to the micro-raster: the end of the list's region.
  uint32_t listSwDrawn(const uint32_t* s, uint32_t phase, uint32_t list) const {
    return (swListMask >> list & 1u) ? std::min(s[STAT_SW_DRAWS + phase * DRAW_LISTS + list], listCapacity[list]) : 0u;
  }

  // This frame builds tile light lists: visbuf path, tiled shading asked for, and point lights to cull.
  bool cullLights(const FrameOptions& options) const {
    return options.path == RenderPath::Visbuf && options.tiledLights && hasPointLights();
  }
  Result<FrameResult> render(const Camera& camera, const FrameOptions& options);
  void recordVisbuf(const FrameOptions& options, uint32_t& used);
  void recordGBufferLighting(uint32_t& used, bool writeAttributes);
  std::vector<passes::ForwardDraw> forwardCull(const Camera& camera, const FrameMath& math,
                                               const FrameOptions& options, FrameStats& stats) const;
  bool cullObject(uint32_t i, const Camera& camera, const FrameMath& math, const FrameOptions& options, FrameStats& st,
                  passes::ForwardDraw& draw, glm::dvec3& centre) const;
  std::vector<passes::TransparentDraw> transparentCull(const Camera& camera, const FrameMath& math,
                                                       const FrameOptions& options, FrameStats& st) const;
  void recordTransparent(const Camera& camera, const FrameMath& math, const FrameOptions& options, FrameStats& st,
                         uint32_t& used);
  // Slots of the draw buffer: [0, capacity) early (or only) phase, [capacity, 2 capacity) late; within a phase
  // the draw lists' regions. Draws a phase actually wrote: min(count, capacity) per list.
  uint32_t listDrawn(const uint32_t* s, uint32_t phase, uint32_t list) const {
    return std::min(s[STAT_LIST_DRAWS + phase * DRAW_LISTS + list], listCapacity[list]);
  }
};

// The "what a user does without us" baseline's per-object test: CPU frustum culling (double precision) and the
// same LOD rule. False: culled. centre: the world bounds centre (transparency sorts by it).
bool Renderer::Impl::cullObject(uint32_t i, const Camera& camera, const FrameMath& math, const FrameOptions& options,
                                FrameStats& st, passes::ForwardDraw& draw, glm::dvec3& centre) const {
  const Object& o = scene.objects[i];
  const Mesh& mesh = scene.meshes[o.mesh];
  double scale = 0.0;
  glm::dvec4 s;
  if (!animation || !animation->skinnedBounds(i, &s, &scale)) {  // skinned: the current pose's bound
    scale = maxScaleOf(o.transform);
    s = objectBoundsWorld(scene, o, scale);
  }
  centre = glm::dvec3(s);
  if (options.cull != CullMode::None && !sphereInFrustum(math, camera, glm::dvec3(s), s.w)) {
    ++st.frustumCulled;
    return false;
  }
  double dist = glm::length(glm::dvec3(s) - camera.position) - s.w;
  uint32_t lod = selectLod(mesh, scale, dist, math, camera.nearPlane, options.lodErrorPixels);
  const gpu::MeshData& md = gpuScene.meshTable[gpuScene.objectMesh[i]];
  draw = {md.lods[lod].indexCount, md.lods[lod].firstIndex, int32_t(md.vertexOffset), i, gpuScene.objectList[i]};
  st.trianglesDrawn += md.lods[lod].indexCount / 3;
  st.lodHistogram[lod]++;
  return true;
}

std::vector<passes::ForwardDraw> Renderer::Impl::forwardCull(const Camera& camera, const FrameMath& math,
                                                             const FrameOptions& options, FrameStats& st) const {
  // One draw per object, grouped by draw list (opaque first, as the visibility pass draws them); BLEND objects
  // are the transparency pass's.
  std::vector<passes::ForwardDraw> out;
  st.lodHistogram.assign(MAX_LODS, 0);
  for (uint32_t i = 0; i < scene.objects.size(); ++i) {
    if (gpuScene.objectList[i] == DRAW_LIST_NONE) continue;
    passes::ForwardDraw d;
    glm::dvec3 centre;
    if (cullObject(i, camera, math, options, st, d, centre)) out.push_back(d);
  }
  if (listMask & ~1u)
    std::stable_sort(out.begin(), out.end(),
                     [](const passes::ForwardDraw& a, const passes::ForwardDraw& b) { return a.list < b.list; });
  st.objectsTested = uint32_t(scene.objects.size());
  st.drawsAppended = st.drawsRendered = uint32_t(out.size());
  return out;
}

std::vector<passes::TransparentDraw> Renderer::Impl::transparentCull(const Camera& camera, const FrameMath& math,
                                                                     const FrameOptions& options,
                                                                     FrameStats& st) const {
  // Culled like the forward path's objects (they are not in the GPU's draw lists), then sorted back to front.
  std::vector<passes::TransparentDraw> out;
  FrameStats mine;  // (their triangles and LODs are reported apart from the opaque draws')
  mine.lodHistogram.assign(MAX_LODS, 0);
  const glm::dvec3 forwardDir = glm::normalize(camera.target - camera.position);
  for (uint32_t i : blendObjects) {
    passes::TransparentDraw t;
    glm::dvec3 centre;
    if (!cullObject(i, camera, math, options, mine, t.draw, centre)) continue;
    const Material& m = scene.materials[scene.objects[i].material];
    // Face culling as an opaque object of the same winding and sidedness (a skinned object: its placement's).
    glm::dmat4 placed = scene.objects[i].transform;
    for (const SkinnedObject& so : scene.skinnedObjects)
      if (so.object == i) placed = so.placement;
    t.draw.list = m.doubleSided                                   ? DRAW_LIST_OPAQUE_DOUBLE_SIDED
                  : glm::determinant(glm::dmat3(placed)) < 0.0 ? DRAW_LIST_OPAQUE_FLIPPED
                                                                  : DRAW_LIST_OPAQUE;
    t.viewDepth = glm::dot(centre - camera.position, forwardDir);
    out.push_back(t);
  }
  passes::sortBackToFront(out);
  st.transparentDraws = uint32_t(out.size());
  st.transparentTriangles = mine.trianglesDrawn;
  return out;
}

void Renderer::Impl::recordTransparent(const Camera& camera, const FrameMath& math, const FrameOptions& options,
                                       FrameStats& st, uint32_t& used) {
  std::vector<passes::TransparentDraw> draws = transparentCull(camera, math, options, st);
  VkCommandBuffer cmd = cmds[used++];
  beginCmd(cmd);
  const bool visbuf = options.path == RenderPath::Visbuf;
  // Colour: the shading pass's storage writes (visbuf) or the forward pass's attachment writes; depth: the last
  // raster's writes, now only tested.
  if (visbuf)
    gpu::imageBarrier(cmd, color, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                      VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  else
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                       VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  constexpr VkPipelineStageFlags2 kDepthStages =
      VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
  gpu::memoryBarrier(cmd, kDepthStages, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, kDepthStages,
                     VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT);
  uint32_t t = timestamps->begin(cmd, "transparent");
  transparent.record(cmd, pipelineLayout, set, color, depth, gpuScene.indices.handle(), draws);
  timestamps->end(cmd, t);
  if (visbuf)  // back to the layout the visbuf path's readback expects
    gpu::imageBarrier(cmd, color, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL,
                      VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT);
  VK_CHECK(vkEndCommandBuffer(cmd));
}

// The GPU-culled frame of the visbuf path, and of the G-buffer baseline (same culling and draw lists; its raster
// writes the attribute targets and its last pass is the deferred lighting instead of the ID resolve).
void Renderer::Impl::recordVisbuf(const FrameOptions& options, uint32_t& used) {
  const uint32_t w = config.width, h = config.height;
  const bool deferred = options.path == RenderPath::GBuffer;
  const bool frozen = options.freezeCulling && haveDraws;
  const bool occlusion = (frozen ? lastCull : options.cull) == CullMode::Occlusion;
  constexpr VkPipelineStageFlags2 kDepthStages =
      VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
  constexpr VkAccessFlags2 kDepthAccess =
      VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
  // MSAA: the multisampled targets (prepareMsaa) replace the single-sample ones in every pass of the frame.
  const bool msaa = options.msaa > 1;
  const gpu::Image& idTarget = msaa ? idsMs : ids;
  const gpu::Image& depthTarget = msaa ? depthMs : depth;

  auto recordCull = [&](uint32_t phase, const char* name) {
    VkCommandBuffer cmd = cmds[used++];
    beginCmd(cmd);
    if (occlusion && phase == CULL_PHASE_LATE) {  // it lists the visible set anew, after the early phase read it
      gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT, 0,
                         VK_PIPELINE_STAGE_2_TRANSFER_BIT, 0);
      resetVisibleList(cmd);
    }
    // Counters reset (setup) and, in the late phase, the pyramid and the early draws' reads.
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT |
                                VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT,
                       VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
                       VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
                           VK_ACCESS_2_SHADER_SAMPLED_READ_BIT | VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT);
    uint32_t t = timestamps->begin(cmd, name);
    if (occlusion && phase == CULL_PHASE_EARLY) {
      cull.recordListed(cmd, pipelineLayout, set, visibleList, 0, CULL_PHASE_EARLY, 0);
    } else {
      cull.record(cmd, pipelineLayout, set, gpuScene.objectCount, phase);
      // The objects the coarse pyramid test left, at a finer level (without a pyramid this frame it lists none).
      if (occlusion && phase == CULL_PHASE_LATE && usePyramid) {
        gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                           VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
                           VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
                               VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT);
        cull.recordListed(cmd, pipelineLayout, set, visibleList, refineListOffset(), CULL_PHASE_LATE, CULL_REFINE);
      }
    }
    timestamps->end(cmd, t);
    VK_CHECK(vkEndCommandBuffer(cmd));
  };
  // The draw lists of a phase, in drawing order (draw buffer regions and counts: the cull pass's).
  auto phaseLists = [&](uint32_t phase) {
    std::vector<passes::VisibilityList> lists;
    for (uint32_t l = 0; l < DRAW_LISTS; ++l)
      if (listCapacity[l] > 0)
        lists.push_back({l, phase * capacity + listFirst[l], STAT_LIST_DRAWS + phase * DRAW_LISTS + l, listCapacity[l]});
    return lists;
  };
  auto recordRaster = [&](uint32_t phase, bool clear, const char* name) {
    VkCommandBuffer cmd = cmds[used++];
    beginCmd(cmd);
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT,
                       VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
    if (clear) {
      if (deferred)
        for (const gpu::Image& t : gbufferTargets)
          gpu::imageBarrier(cmd, t, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                            VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                            VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      else
        gpu::imageBarrier(cmd, idTarget, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                          VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_TRANSFER_BIT, 0,
                          VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      gpu::imageBarrier(cmd, depthTarget, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                        kDepthStages | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, 0, kDepthStages, kDepthAccess);
    } else {
      // Late phase: keep the early phase's IDs and depth (the pyramid pass read the depth).
      gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                         VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                         VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      if (frozen || !usePyramid)  // the depth stayed an attachment
        gpu::memoryBarrier(cmd, kDepthStages, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, kDepthStages, kDepthAccess);
      else
        gpu::imageBarrier(cmd, depthTarget, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                          VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, 0,
                          kDepthStages, kDepthAccess);
    }
    uint32_t t = timestamps->begin(cmd, name);
    // The same draw lists for either raster; only the targets differ.
    auto common = [&](auto& in) {
      in.depth = &depthTarget;
      in.indexBuffer = gpuScene.indices.handle();
      in.draws = draws.handle();
      in.drawCount = stats.handle();
      in.lists = phaseLists(phase);
      in.clear = clear;
      in.countOverdraw = options.countOverdraw;
    };
    if (deferred) {
      passes::GBufferInputs in;
      for (uint32_t i = 0; i < GBUFFER_TARGETS; ++i) in.targets[i] = &gbufferTargets[i];
      common(in);
      gbuffer.record(cmd, pipelineLayout, set, in);
    } else {
      passes::VisibilityInputs in;
      in.ids = &idTarget;
      common(in);
      (msaa ? visibilityMs : visibility).record(cmd, pipelineLayout, set, in);
    }
    timestamps->end(cmd, t);
    VK_CHECK(vkEndCommandBuffer(cmd));
  };

  // Software micro-raster after each raster phase: the routed draws into the 64-bit buffer (cleared by the first
  // phase), then merged into the IDs and depth that the raster left as attachments.
  const bool sw = !deferred && swOn;
  auto recordSw = [&](uint32_t phase, bool clear, const char* name, const char* mergeName) {
    VkCommandBuffer cmd = cmds[used++];
    beginCmd(cmd);
    if (clear) {
      vkCmdFillBuffer(cmd, swRaster.buffer.handle(), 0, VK_WHOLE_SIZE, 0);
    }
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT |
                                VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                       VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
                           VK_ACCESS_2_SHADER_STORAGE_READ_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
                       VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
                           VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT);
    uint32_t t = timestamps->begin(cmd, name);
    swRaster.recordRaster(cmd, pipelineLayout, set, phase, stats);
    timestamps->end(cmd, t);
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT | kDepthStages,
                       VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT | kDepthStages,
                       VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT | kDepthAccess);
    t = timestamps->begin(cmd, mergeName);
    swRaster.recordMerge(cmd, pipelineLayout, set, idTarget, depthTarget, stats, phase);
    timestamps->end(cmd, t);
    VK_CHECK(vkEndCommandBuffer(cmd));
  };
  auto recordRasterPhase = [&](uint32_t phase, bool clear, const char* name) {
    recordRaster(phase, clear, name);
    if (sw)
      recordSw(phase, clear, phase == CULL_PHASE_LATE ? "sw raster late" : "sw raster",
               phase == CULL_PHASE_LATE ? "sw merge late" : "sw merge");
  };

  const char* rasterOnly = deferred ? "gbuffer" : "visibility";
  const char* rasterEarly = deferred ? "gbuffer early" : "raster early";
  const char* rasterLate = deferred ? "gbuffer late" : "raster late";
  if (frozen) {  // the draw lists and their counts are the frozen frame's: raster them as they are
    recordRasterPhase(CULL_PHASE_EARLY, true, occlusion ? rasterEarly : rasterOnly);
    if (occlusion) recordRasterPhase(CULL_PHASE_LATE, false, rasterLate);
  } else if (!occlusion) {
    recordCull(CULL_PHASE_EARLY, "cull");
    recordRasterPhase(CULL_PHASE_EARLY, true, rasterOnly);
  } else {
    recordCull(CULL_PHASE_EARLY, "cull early");
    recordRasterPhase(CULL_PHASE_EARLY, true, rasterEarly);
    if (!usePyramid) {  // the late phase runs frustum + sub-pixel tests only
      recordCull(CULL_PHASE_LATE, "cull late");
      recordRasterPhase(CULL_PHASE_LATE, false, rasterLate);
    }
  }
  if (!frozen && occlusion && usePyramid) {
    VkCommandBuffer cmd = cmds[used++];
    beginCmd(cmd);
    gpu::imageBarrier(cmd, depthTarget, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                      kDepthStages, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                      VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    // The previous frame's late cull read the pyramid that this pass overwrites.
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    uint32_t t = timestamps->begin(cmd, "depth pyramid");
    pyramid.record(cmd, msaa);
    timestamps->end(cmd, t);
    VK_CHECK(vkEndCommandBuffer(cmd));
    recordCull(CULL_PHASE_LATE, "cull late");
    recordRasterPhase(CULL_PHASE_LATE, false, rasterLate);
  }
  if (deferred) {
    recordGBufferLighting(used, options.readAttributes);
    return;
  }

  if (cullLights(options)) {  // tile light lists from the final depth
    VkCommandBuffer cmd = cmds[used++];
    beginCmd(cmd);
    gpu::imageBarrier(cmd, depthTarget, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                      kDepthStages, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                      VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    // The previous frame's shading read the lists this pass rewrites.
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT,
                       VK_PIPELINE_STAGE_2_TRANSFER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                       VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    uint32_t t = timestamps->begin(cmd, "light cull");
    lightCull.record(cmd, pipelineLayout, set, msaa);
    timestamps->end(cmd, t);
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_TRANSFER_BIT,
                       VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_TRANSFER_READ_BIT);
    VK_CHECK(vkEndCommandBuffer(cmd));
  }

  // The IDs become the sampled input of the classification (if any) and the shading.
  const bool classified = shadingFor(options) == ShadingMode::Classified;
  VkCommandBuffer cmd = cmds[used++];
  beginCmd(cmd);
  gpu::imageBarrier(cmd, idTarget, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                    VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                    VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  if (classified) {
    uint32_t t = timestamps->begin(cmd, "classify");
    classify.recordClassify(cmd, pipelineLayout, set);
    timestamps->end(cmd, t);
    VK_CHECK(vkEndCommandBuffer(cmd));
    cmd = cmds[used++];
    beginCmd(cmd);
  }
  // shade (it reads the cull pass's draws through a texel view)
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  gpu::imageBarrier(cmd, color, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                    VK_PIPELINE_STAGE_2_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_2_TRANSFER_BIT,
                    VK_ACCESS_2_TRANSFER_WRITE_BIT);
  uint32_t t = timestamps->begin(cmd, "shade");
  VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdClearColorImage(cmd, color.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &kBackground, 1, &range);
  gpu::imageBarrier(cmd, color, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL,
                    VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                    VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  if (options.readAttributes) {
    vkCmdFillBuffer(cmd, attributes.handle(), 0, VK_WHOLE_SIZE, 0);
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  }
  if (msaa) {  // its own counter (a frozen frame keeps the cull counts, not this one); reads the cleared colour
    vkCmdFillBuffer(cmd, stats.handle(), STAT_PER_SAMPLE_PIXELS * sizeof(uint32_t), sizeof(uint32_t), 0);
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                       VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  }
  if (classified)
    classify.recordShade(cmd, pipelineLayout, set);
  else
    shade.record(cmd, pipelineLayout, set, w, h,
                 msaa                     ? passes::ShadePass::Msaa
                 : options.readAttributes ? passes::ShadePass::Attributes
                                          : passes::ShadePass::Plain);
  timestamps->end(cmd, t);
  if (msaa && options.readIds) shade.recordSampleIds(cmd, pipelineLayout, set, w, h);  // (untimed) -> attributes
  VK_CHECK(vkEndCommandBuffer(cmd));
}

// G-buffer baseline: after the last raster phase the targets and the depth become sampled images of the
// lighting pass, which writes the covered pixels of the (background-cleared) colour image.
void Renderer::Impl::recordGBufferLighting(uint32_t& used, bool writeAttributes) {
  VkCommandBuffer cmd = cmds[used++];
  beginCmd(cmd);
  for (const gpu::Image& t : gbufferTargets)
    gpu::imageBarrier(cmd, t, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                      VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  gpu::imageBarrier(cmd, depth, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                    VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  gpu::imageBarrier(cmd, color, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                    VK_PIPELINE_STAGE_2_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
  uint32_t t = timestamps->begin(cmd, "lighting");
  VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdClearColorImage(cmd, color.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &kBackground, 1, &range);
  gpu::imageBarrier(cmd, color, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL,
                    VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                    VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  if (writeAttributes) {
    vkCmdFillBuffer(cmd, attributes.handle(), 0, VK_WHOLE_SIZE, 0);
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  }
  gbufferLighting.record(cmd, pipelineLayout, set, config.width, config.height, writeAttributes);
  timestamps->end(cmd, t);
  VK_CHECK(vkEndCommandBuffer(cmd));
}

Result<FrameResult> Renderer::Impl::render(const Camera& camera, const FrameOptions& options) {
  using Clock = std::chrono::steady_clock;
  for (double v : {camera.position.x, camera.position.y, camera.position.z, camera.target.x, camera.target.y,
                   camera.target.z, camera.fovY, camera.nearPlane})
    if (!std::isfinite(v)) return makeError(ErrorCode::InvalidArgument, "camera has a non-finite component");
  if (glm::length(camera.target - camera.position) <= 0.0 || camera.nearPlane <= 0.0 || camera.fovY <= 0.0 ||
      camera.fovY >= M_PI)
    return makeError(ErrorCode::InvalidArgument, "camera: target must differ from position, near > 0, 0 < fov < 180 deg");
  if (glm::length(glm::cross(glm::normalize(camera.target - camera.position), glm::normalize(camera.up))) < 1e-9)
    return makeError(ErrorCode::InvalidArgument, "camera: view direction is parallel to the up vector");

  if (options.readIds && options.path == RenderPath::GBuffer)
    return makeError(ErrorCode::InvalidArgument, "the G-buffer path writes no IDs (readIds: visbuf or forward)");
  if (options.path == RenderPath::GBuffer) ensureGBufferTargets();  // once: not part of the frame's CPU time
  if (Status s = checkMsaa(options); !s.ok()) return s.error();
  if (options.swRaster != SwRasterMode::Off && !(options.swRasterPixels > 0.0f && options.swRasterPixels <= SW_RASTER_MAX_EXTENT - 2))
    return makeError(ErrorCode::InvalidArgument, fmt::format("micro-raster size bound {} px outside (0, {}]",
                                                             options.swRasterPixels, SW_RASTER_MAX_EXTENT - 2));
  prepareMsaa(options);  // once per sample count (and size)
  const bool msaa = options.msaa > 1;
  if (shadingFor(options) == ShadingMode::Classified) ensureClassify();  // likewise

  const auto t0 = Clock::now();
  const uint32_t w = config.width, h = config.height;
  const bool gpuCulled = options.path != RenderPath::Forward;  // visbuf and G-buffer: cull pass + draw lists
  const bool frozen = gpuCulled && options.freezeCulling && haveDraws;
  const bool occlusionFrame = gpuCulled && !frozen && options.cull == CullMode::Occlusion;
  // The micro-raster this frame (a frozen frame redraws what its frame routed); its buffer once used.
  swOn = frozen ? lastSwOn : swActive(options) && swSkipFrames == 0;
  if (swOn && swRaster.ensureBuffer(device, config.width, config.height)) writeDescriptors();
  usePyramid = occlusionFrame && (options.readPyramid || !(options.skipUselessPyramid && pyramidSkipFrames > 0));
  const bool readAttributes = options.readAttributes && gpuCulled;  // G-buffer: position and depth only
  const VkDeviceSize attributeBytes = VkDeviceSize(w) * h * ATTRIBUTE_FLOATS * sizeof(float);
  // MSAA readIds: the sample-ID copy goes through the attribute buffer (2 uints per sample).
  const VkDeviceSize sampleIdBytes = msaa && options.readIds ? VkDeviceSize(w) * h * options.msaa * 8 : 0;
  if (std::max(readAttributes ? attributeBytes : 0, sampleIdBytes) > attributes.size()) {
    resizeAttributes(std::max(attributeBytes, sampleIdBytes));  // no frame is in flight: safe to rewrite the set
    writeDescriptors();
  }
  if (idsReadback.size() < sampleIdBytes)
    idsReadback = gpu::Buffer(device, sampleIdBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
  FrameMath math = computeFrameMath(camera, w, h);
  gpu::FrameData fd = frameData(camera, math, options);
  std::memcpy(frameBuffer.mapped(), &fd, sizeof(fd));

  FrameResult result;
  FrameStats& st = result.stats;
  st.device = device.name();
  st.path = options.path;
  st.width = w;
  st.height = h;
  st.objects = gpuScene.objectCount;
  st.drawCapacity = capacity;
  st.ids = encoding;
  st.sceneBytes = gpuScene.bytes + (animation ? animation->bytes() : 0);
  st.textureClasses = uint32_t(gpuScene.textureClasses.size());
  st.textureBytes = gpuScene.textureBytes;
  st.texturesDecompressed = gpuScene.texturesDecompressed;
  st.pointLights = uint32_t(scene.pointLights.size());
  st.lightBytes = hasPointLights() ? pointLights.size() + lightCull.tiles().size() : 0;
  st.lightsCulled = cullLights(options);
  st.msaaSamples = options.msaa;
  st.shading = shadingFor(options);

  uint32_t used = 0;
  // setup: queries, counters
  VkCommandBuffer cmd = cmds[used++];
  beginCmd(cmd);
  timestamps->reset(cmd);
  if (!frozen) {  // frozen: keep the counts (and the micro-raster's arguments)
    vkCmdFillBuffer(cmd, stats.handle(), 0, STAT_COUNT * sizeof(uint32_t), 0);
    const uint32_t args[2 * SW_ARGS_UINTS] = {0, 1, 1, 0, 1, 0, 0, 0, 0, 1, 1, 0, 1, 0, 0, 0};
    vkCmdUpdateBuffer(cmd, stats.handle(), SW_ARGS * sizeof(uint32_t), sizeof(args), args);
  }
  if (options.countOverdraw) {
    VkClearColorValue zero{};
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, overdraw.handle(), VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
    gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                       VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  }
  if (historyDirty) {
    vkCmdFillBuffer(cmd, history.handle(), 0, VK_WHOLE_SIZE, 0);
    resetVisibleList(cmd);
    historyDirty = false;
  }
  VK_CHECK(vkEndCommandBuffer(cmd));

  if (animation) {  // skinning: only when the pose changed (a static scene has no AnimationState at all)
    st.skinnedInstances = animation->instanceCount();
    st.skinnedVertices = animation->vertexCount();
    st.skinBounds = skinBoundsName(config.skinBounds);
    if (animation->update(options.animationTime)) {
      st.skinned = true;
      st.animationCpuMs = animation->lastUpdateMs();
      cmd = cmds[used++];
      beginCmd(cmd);
      uint32_t t = timestamps->begin(cmd, "skin");
      skin.record(cmd, animation->instanceCount(), animation->maxVertices());
      timestamps->end(cmd, t);
      // Regions and mesh slots are read by every later pass (cull, raster, shading, forward).
      gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                         VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT);
      VK_CHECK(vkEndCommandBuffer(cmd));
    }
  }
  const gpu::Image* colorSource = &color;
  const CullMode effectiveCull = frozen ? lastCull : options.cull;
  const bool builtPyramid = usePyramid;
  st.pyramidSkipped = occlusionFrame && !usePyramid;
  st.cullingFrozen = frozen;
  st.pyramidLevels = builtPyramid ? pyramid.levels() : 0;
  if (gpuCulled) {
    FrameOptions visbufOptions = options;
    visbufOptions.readAttributes = readAttributes;
    recordVisbuf(visbufOptions, used);
    haveDraws = true;
    lastCull = effectiveCull;
    st.rasterBytesPerFragment =
        (options.path == RenderPath::GBuffer ? gbuffer.formats.bytesPerPixel() : gpu::formatBytes(ids.format())) +
        4 /*depth*/;
    st.targetBytesPerPixel = st.rasterBytesPerFragment * options.msaa + 8 /*colour*/;  // raster targets per sample
  } else {
    std::vector<passes::ForwardDraw> fdraws = forwardCull(camera, math, options, st);
    if (options.readDraws)
      for (const auto& d : fdraws) {
        const gpu::MeshData& md = gpuScene.meshTable[gpuScene.objectMesh[d.objectId]];
        uint32_t lod = 0;
        while (lod + 1 < md.lodCount && md.lods[lod].firstIndex != d.firstIndex) ++lod;
        result.drawnObjects.push_back(d.objectId);
        result.drawnLods.push_back(lod);
      }
    cmd = cmds[used++];
    beginCmd(cmd);
    // MSAA: multisampled colour + depth, the colour averaged into `color` at the end (hardware resolve).
    const gpu::Image& colorTarget = msaa ? colorMs : color;
    const gpu::Image& depthTarget = msaa ? depthMs : depth;
    gpu::imageBarrier(cmd, color, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                      VK_PIPELINE_STAGE_2_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                      VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    if (msaa)
      gpu::imageBarrier(cmd, colorMs, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                        VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, 0,
                        VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    gpu::imageBarrier(cmd, depthTarget, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                      VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                      VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    uint32_t t = timestamps->begin(cmd, "forward");
    if (options.readIds) {
      if (!forwardIds)
        forwardIds = gpu::Image(device, VK_FORMAT_R32G32_UINT, w, h,
                                VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                VK_IMAGE_ASPECT_COLOR_BIT);
      gpu::imageBarrier(cmd, forwardIds, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                        VK_PIPELINE_STAGE_2_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                        VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    }
    (msaa ? forwardMs : forward)
        .record(cmd, pipelineLayout, set, colorTarget, kBackground, depthTarget, gpuScene.indices.handle(), fdraws,
                options.readIds ? &forwardIds : nullptr, options.countOverdraw, msaa ? &color : nullptr);
    timestamps->end(cmd, t);
    VK_CHECK(vkEndCommandBuffer(cmd));
    st.targetBytesPerPixel = (4 /*depth*/ + 8 /*colour*/) * options.msaa + (msaa ? 8 /*resolved colour*/ : 0);
    st.rasterBytesPerFragment = 4 /*depth*/ + 8 /*colour*/;
  }
  if (!blendObjects.empty()) recordTransparent(camera, math, options, st, used);

  // readback
  cmd = cmds[used++];
  beginCmd(cmd);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT, VK_PIPELINE_STAGE_2_TRANSFER_BIT,
                VK_ACCESS_2_TRANSFER_READ_BIT);
  VkBufferCopy statsCopy{0, 0, STAT_COUNT * sizeof(uint32_t)};
  vkCmdCopyBuffer(cmd, stats.handle(), statsReadback.handle(), 1, &statsCopy);
  if (st.lightsCulled) lightCull.recordReadback(cmd);
  if (options.readColor) {
    VkImageLayout from = gpuCulled ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    gpu::imageBarrier(cmd, *colorSource, from, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                      VK_ACCESS_2_MEMORY_WRITE_BIT, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    copyImageToBuffer(cmd, *colorSource, colorReadback);
  }
  const bool readIds = options.readIds;
  const bool readDraws = (readIds || options.readDraws) && gpuCulled;
  if (readDraws) {
    if (!drawsReadback)
      drawsReadback = gpu::Buffer(device, draws.size(), VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
    VkBufferCopy dc{0, 0, draws.size()};
    vkCmdCopyBuffer(cmd, draws.handle(), drawsReadback.handle(), 1, &dc);
  }
  const bool readPyramid = builtPyramid && options.readPyramid;
  std::vector<std::pair<uint32_t, uint32_t>> pyramidSizes;
  if (readPyramid) {
    uint32_t lw = w, lh = h;
    VkDeviceSize offset = 0;
    std::vector<VkBufferImageCopy> regions;
    for (uint32_t k = 0; k < pyramid.levels(); ++k) {
      VkBufferImageCopy region{};
      region.bufferOffset = offset;
      region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, k, 0, 1};
      region.imageExtent = {lw, lh, 1};
      regions.push_back(region);
      pyramidSizes.emplace_back(lw, lh);
      offset += VkDeviceSize(lw) * lh * 4;
      lw = (lw + 1) / 2;
      lh = (lh + 1) / 2;
    }
    if (!pyramidReadback || pyramidReadback.size() < offset)
      pyramidReadback = gpu::Buffer(device, offset, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
    gpu::imageBarrier(cmd, pyramid.pyramid(), VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    vkCmdCopyImageToBuffer(cmd, pyramid.pyramid().handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                           pyramidReadback.handle(), uint32_t(regions.size()), regions.data());
    gpu::imageBarrier(cmd, pyramid.pyramid(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL,
                      VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  }
  if (options.countOverdraw) {
    if (!overdrawReadback)
      overdrawReadback = gpu::Buffer(device, VkDeviceSize(w) * h * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                     gpu::MemoryUse::HostVisible);
    gpu::imageBarrier(cmd, overdraw, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                      VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    copyImageToBuffer(cmd, overdraw, overdrawReadback);
    gpu::imageBarrier(cmd, overdraw, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL,
                      VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
                      VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0);
  }
  if (readAttributes) {
    if (!attributesReadback)
      attributesReadback = gpu::Buffer(device, attributes.size(), VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                       gpu::MemoryUse::HostVisible);
    VkBufferCopy ac{0, 0, attributeBytes};
    vkCmdCopyBuffer(cmd, attributes.handle(), attributesReadback.handle(), 1, &ac);
  }
  if (readIds && options.path == RenderPath::Visbuf && msaa) {  // the sample-ID copy (shading command buffer)
    VkBufferCopy c{0, 0, sampleIdBytes};
    vkCmdCopyBuffer(cmd, attributes.handle(), idsReadback.handle(), 1, &c);
  } else if (readIds && options.path == RenderPath::Visbuf) {
    gpu::imageBarrier(cmd, ids, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_TRANSFER_BIT,
                      VK_ACCESS_2_TRANSFER_READ_BIT);
    copyImageToBuffer(cmd, ids, idsReadback);
  } else if (readIds) {
    gpu::imageBarrier(cmd, forwardIds, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                      VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    copyImageToBuffer(cmd, forwardIds, idsReadback);
  }
  VK_CHECK(vkEndCommandBuffer(cmd));

  const auto t1 = Clock::now();
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = used;
  si.pCommandBuffers = cmds.data();
  VK_CHECK(vkResetFences(device.device(), 1, &fence));
  VK_CHECK(vkQueueSubmit(device.queue(), 1, &si, fence));
  VK_CHECK(vkWaitForFences(device.device(), 1, &fence, VK_TRUE, UINT64_MAX));
  const auto t2 = Clock::now();

  st.passMs = timestamps->read();
  if (st.lightsCulled) {
    const passes::LightCullStats ls = lightCull.stats();
    st.lightTileOverflow = ls.overflowTiles;
    st.lightsDropped = ls.droppedLights;
    st.maxLightsPerTile = ls.maxPerTile;
    st.meanLightsPerTile = double(ls.pairs) / (double(lightCull.tilesX()) * lightCull.tilesY());
  }
  for (auto& p : st.passMs) st.gpuMs += p.second;
  if (st.shading == ShadingMode::Classified) {
    passes::ClassifyStats cs = classify.stats();
    st.materialsPresent = cs.materialsPresent;
    st.classifiedTiles = cs.pairs;
    st.materialTiles = std::move(cs.tiles);
    st.materialPixels = std::move(cs.pixels);
  }
  if (gpuCulled) {
    const uint32_t* s = static_cast<const uint32_t*>(statsReadback.mapped());
    st.perSamplePixels = msaa ? s[STAT_PER_SAMPLE_PIXELS] : 0;
    st.objectsTested = gpuScene.objectCount;
    st.frustumCulled = s[STAT_FRUSTUM_CULLED];
    st.occlusionCulled = s[STAT_OCCLUSION_CULLED];
    st.subpixelCulled = s[STAT_SUBPIXEL_CULLED];
    st.refineTested = s[STAT_REFINE_TESTED];
    st.refineOccluded = s[STAT_REFINE_OCCLUDED];
    st.drawsEarly = st.drawsLate = 0;
    for (uint32_t l = 0; l < DRAW_LISTS; ++l) {
      st.drawsEarly += listDrawn(s, CULL_PHASE_EARLY, l) + listSwDrawn(s, CULL_PHASE_EARLY, l);
      st.drawsLate += listDrawn(s, CULL_PHASE_LATE, l) + listSwDrawn(s, CULL_PHASE_LATE, l);
      st.swDraws += listSwDrawn(s, CULL_PHASE_EARLY, l) + listSwDrawn(s, CULL_PHASE_LATE, l);
    }
    st.swRaster = swOn;
    st.swTriangles = s[STAT_SW_TRIANGLES];
    st.swOversize = s[STAT_SW_OVERSIZE];
    // "Skip what the scene does not need": a frame whose micro-raster took nothing (Auto on a GPU: less than pays
    // for its merges) routes everything to the hardware raster for a while, then probes again.
    if (!frozen) {
      const uint64_t worth = options.swRaster == SwRasterMode::Auto && !device.isCpu() ? kGpuSwMinTriangles : 1;
      if (swOn)
        swSkipFrames = st.swTriangles < worth ? kSwProbeInterval : 0;
      else if (swSkipFrames > 0)
        --swSkipFrames;
      lastSwOn = swOn;
    }
    st.drawsAppended = s[STAT_DRAW_COUNT] + s[STAT_DRAW_COUNT_LATE];
    st.drawsRendered = st.drawsEarly + st.drawsLate;
    st.drawOverflow = s[STAT_DRAW_OVERFLOW];
    st.trianglesDrawn = s[STAT_TRIANGLES_DRAWN];
    st.lodHistogram.assign(s + STAT_LOD_HISTOGRAM, s + STAT_LOD_HISTOGRAM + MAX_LODS);
    // "Skip what the scene does not need": a pyramid that hid nothing is not built again for a while.
    // Only a pyramid built from a non-empty early phase is evidence (a first frame or a cut has none).
    if (usePyramid)
      pyramidSkipFrames =
          options.skipUselessPyramid && st.drawsEarly > 0 && st.occlusionCulled == 0 ? kPyramidProbeInterval : 0;
    else if (pyramidSkipFrames > 0)
      --pyramidSkipFrames;
  }
  while (!st.lodHistogram.empty() && st.lodHistogram.back() == 0) st.lodHistogram.pop_back();

  result.width = w;
  result.height = h;
  const size_t pixels = size_t(w) * h;
  if (options.readColor) {
    result.color.resize(pixels * 4);
    const uint16_t* half = static_cast<const uint16_t*>(colorReadback.mapped());
    for (size_t i = 0; i < pixels * 4; ++i) result.color[i] = glm::unpackHalf1x16(half[i]);
  }
  if (readDraws) {
    const auto* dr = static_cast<const gpu::DrawCommand*>(drawsReadback.mapped());
    auto add = [&](const gpu::DrawCommand& d) {
      result.drawnObjects.push_back(d.firstInstance);
      const gpu::MeshData& md = gpuScene.meshTable[gpuScene.objectMesh[d.firstInstance]];
      uint32_t lod = 0;
      while (lod + 1 < md.lodCount && md.lods[lod].firstIndex != d.firstIndex) ++lod;
      result.drawnLods.push_back(lod);
    };
    const uint32_t* s = static_cast<const uint32_t*>(statsReadback.mapped());
    for (uint32_t phase : {CULL_PHASE_EARLY, CULL_PHASE_LATE})
      for (uint32_t l = 0; l < DRAW_LISTS; ++l) {
        for (uint32_t i = 0; i < listDrawn(s, phase, l); ++i) add(dr[phase * capacity + listFirst[l] + i]);
        for (uint32_t i = 0; i < listSwDrawn(s, phase, l); ++i)
          add(dr[phase * capacity + listFirst[l] + listCapacity[l] - 1 - i]);
      }
  }
  if (readPyramid) {
    const float* p = static_cast<const float*>(pyramidReadback.mapped());
    for (auto [lw, lh] : pyramidSizes) {
      result.pyramid.push_back({lw, lh, std::vector<float>(p, p + size_t(lw) * lh)});
      p += size_t(lw) * lh;
    }
  }
  if (options.countOverdraw) {
    const uint32_t* o = static_cast<const uint32_t*>(overdrawReadback.mapped());
    result.overdraw.assign(o, o + pixels);
    uint64_t fragments = 0, covered = 0;
    for (uint32_t n : result.overdraw) {
      fragments += n;
      covered += n > 0;
    }
    st.rasterWritesPerPixel = double(fragments) / double(pixels);
    const double resolveBytes = gpuCulled ? 8.0 * double(covered) / double(pixels) : 0.0;  // colour, covered only
    // Classified shading also writes its tile list (4 B per (tile, material) pair) and the per-material records.
    const double classifyBytes =
        st.shading == ShadingMode::Classified
            ? (4.0 * st.classifiedTiles + double(sizeof(gpu::MaterialTiles)) * st.materialTiles.size()) / double(pixels)
            : 0.0;
    st.bytesWrittenPerPixel = st.rasterWritesPerPixel * st.rasterBytesPerFragment + resolveBytes + classifyBytes;
  }
  if (readAttributes) {
    const float* a = static_cast<const float*>(attributesReadback.mapped());
    result.attributes.assign(a, a + pixels * ATTRIBUTE_FLOATS);
  }
  if (readIds && options.path == RenderPath::Forward) {  // already (object + 1, triangle)
    const uint32_t* raw = static_cast<const uint32_t*>(idsReadback.mapped());
    result.ids.assign(raw, raw + pixels * 2);
  } else if (readIds) {
    const size_t samples = size_t(options.msaa);  // MSAA: every sample (2 uints each, like wide IDs)
    result.ids.assign(pixels * samples * 2, 0);
    const uint32_t* s = static_cast<const uint32_t*>(statsReadback.mapped());
    auto slotWritten = [&](uint32_t slot) {  // within the part of its list's region the cull pass wrote
      if (slot >= 2 * capacity) return false;
      const uint32_t phase = slot < capacity ? 0 : 1, local = slot - phase * capacity;
      for (uint32_t l = 0; l < DRAW_LISTS; ++l)
        if (local >= listFirst[l] && local < listFirst[l] + listCapacity[l])
          return local - listFirst[l] < listDrawn(s, phase, l) ||
                 listFirst[l] + listCapacity[l] - local <= listSwDrawn(s, phase, l);
      return false;
    };
    const uint32_t* raw = static_cast<const uint32_t*>(idsReadback.mapped());
    const auto* dr = static_cast<const gpu::DrawCommand*>(drawsReadback.mapped());
    const size_t stride = encoding.wide || msaa ? 2 : 1;  // the sample-ID copy writes (x, y) even for r32ui
    for (size_t i = 0; i < pixels * samples; ++i) {
      uint32_t slot, tri;
      if (encoding.wide) {
        if (raw[2 * i] == VIS_NOTHING) continue;
        slot = raw[2 * i] - 1;
        tri = raw[2 * i + 1];
      } else {
        if (raw[stride * i] == VIS_NOTHING) continue;
        uint32_t v = raw[stride * i] - 1;
        slot = v >> encoding.triangleBits;
        tri = v & ((1u << encoding.triangleBits) - 1u);
      }
      if (!slotWritten(slot)) {  // GPU misbehaved: loud
        result.ids[2 * i] = 0xFFFFFFFFu;
        continue;
      }
      result.ids[2 * i] = dr[slot].firstInstance + 1;
      result.ids[2 * i + 1] = tri;
    }
  }
  const auto t3 = Clock::now();
  st.cpuRecordMs = std::chrono::duration<double, std::milli>(t1 - t0).count();
  st.wallMs = std::chrono::duration<double, std::milli>(t3 - t1).count();
  (void)t2;
  return result;
}

Renderer::Renderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Renderer::~Renderer() = default;

Result<std::unique_ptr<Renderer>> Renderer::create(gpu::Device& device, const Scene& scene,
                                                   const RendererConfig& config) {
  if (config.width == 0 || config.height == 0 || config.width > 16384 || config.height > 16384)
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("image size {}x{} outside 1..16384", config.width, config.height));
  auto impl = std::make_unique<Impl>(device, scene);
  impl->config = config;
  Result<GpuScene> g = uploadScene(device, scene);
  if (!g) return g.error();
  impl->gpuScene = std::move(g.value());
  // Default capacity: one draw per object, as far as one descriptor range holds both phases' draw lists
  // (beyond that, overflow is counted and reported like any capacity overflow).
  const uint64_t maxRange = device.properties().limits.maxStorageBufferRange;
  impl->objectSplit = objectWindowSplit(maxRange, impl->gpuScene.objectCount);
  impl->vertexShift = vertexWindowShift(maxRange);
  // Draw lists: each list's capacity is its object count (a list can never hold more), capped by
  // config.drawCapacity (per list) or, by default, shared out so that both phases fit one descriptor range.
  std::array<uint64_t, DRAW_LISTS> listObjects{};
  uint64_t listed = 0;
  for (uint32_t i = 0; i < impl->gpuScene.objectCount; ++i) {
    const uint32_t l = impl->gpuScene.objectList[i];
    if (l == DRAW_LIST_NONE)
      impl->blendObjects.push_back(i);
    else
      ++listObjects[l], ++listed;
  }
  const uint64_t rangeSlots = maxRange / (2 * sizeof(gpu::DrawCommand));
  for (uint32_t l = 0; l < DRAW_LISTS; ++l) {
    uint64_t c = listObjects[l];
    if (config.drawCapacity)
      c = std::min<uint64_t>(c, config.drawCapacity);
    else if (listed > rangeSlots)
      c = std::max<uint64_t>(c ? 1 : 0, c * rangeSlots / listed);
    impl->listFirst[l] = impl->capacity;
    impl->listCapacity[l] = uint32_t(c);
    impl->capacity += uint32_t(c);
    if (c) impl->listMask |= 1u << l;
    // The micro-raster fills a list's region from its end, so only where the region holds every object of the list.
    if (c && c == listObjects[l] && !passes::drawListMasked(l)) impl->swListMask |= 1u << l;
  }
  impl->capacity = std::max(impl->capacity, 1u);  // (a scene of only BLEND objects: no list, one unused slot)
  // Two regions of `capacity` commands: the early (or only) phase, then the late phase.
  const uint64_t drawBytes = 2 * uint64_t(impl->capacity) * sizeof(gpu::DrawCommand);
  if (drawBytes > device.properties().limits.maxStorageBufferRange)
    return makeError(ErrorCode::CapacityExceeded,
                     fmt::format("draw capacity {} needs {:.1f} MiB, over maxStorageBufferRange", impl->capacity,
                                 drawBytes / 1048576.0));
  impl->encoding = chooseIdEncoding(2 * impl->capacity, impl->gpuScene.maxTrianglesPerDraw, config.forceWideIds);
  impl->msaaCounts = supportedMsaaSamples(device);
  impl->createLayouts();
  // Descriptor windows only when needed: a scene whose objects and vertices fit one range reads them directly.
  const bool windowed = impl->objectSplit < impl->gpuScene.objectCount ||
                        impl->gpuScene.vertices.size() > (VkDeviceSize(sizeof(gpu::Vertex)) << impl->vertexShift);
  const uint32_t w = windowed ? 1u : 0u;
  // Texel views: the scene's records and the draws (five words each) within maxTexelBufferElements.
  const VkDeviceSize maxTexels = device.properties().limits.maxTexelBufferElements;
  const bool texels = impl->gpuScene.texels && !windowed && drawBytes / 4 <= maxTexels;
  const gpu::Specialization textured(w, uint32_t(impl->gpuScene.textureClasses.size()),
                                     impl->gpuScene.skinned.empty() ? 0u : 1u, texels ? 1u : 0u);
  impl->cull = passes::CullPass::create(device, impl->pipelineLayout, textured);
  impl->visibility = passes::VisibilityPass::create(device, impl->pipelineLayout, textured, impl->listMask);
  impl->shade = passes::ShadePass::create(device, impl->pipelineLayout, textured);
  if (impl->swListMask) impl->swRaster = passes::SwRasterPass::create(device, impl->pipelineLayout, textured);
  impl->forward = passes::ForwardPass::create(device, impl->pipelineLayout, textured, impl->listMask);
  if (!impl->blendObjects.empty())
    impl->transparent = passes::TransparentPass::create(device, impl->pipelineLayout, textured);
  std::array<glm::uvec4, DRAW_LISTS> lists{};
  for (uint32_t l = 0; l < DRAW_LISTS; ++l)
    lists[l] = {impl->listFirst[l], impl->capacity + impl->listFirst[l], impl->listCapacity[l],
                impl->swListMask >> l & 1u};
  impl->drawLists = gpu::Buffer(device, sizeof(lists), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, gpu::MemoryUse::HostVisible);
  std::memcpy(impl->drawLists.mapped(), lists.data(), sizeof(lists));
  impl->textured = textured;  // the G-buffer pipelines are created by the first G-buffer frame
  impl->frameBuffer = gpu::Buffer(device, sizeof(gpu::FrameData), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                                  gpu::MemoryUse::HostVisible);
  impl->draws = gpu::Buffer(device, drawBytes,
                            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT,
                            gpu::MemoryUse::DeviceLocal);
  impl->drawTexels = gpu::BufferView(device, impl->draws, VK_FORMAT_R32_UINT, 0,
                                     std::min<VkDeviceSize>(drawBytes / 4, maxTexels) * 4);
  impl->stats = gpu::Buffer(device, (SW_ARGS + 2 * SW_ARGS_UINTS) * sizeof(uint32_t),
                            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                            gpu::MemoryUse::DeviceLocal);
  impl->statsReadback = gpu::Buffer(device, STAT_COUNT * sizeof(uint32_t), VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                    gpu::MemoryUse::HostVisible);
  impl->history = gpu::Buffer(device, std::max<uint64_t>(16, uint64_t(impl->gpuScene.objectCount) * 4),
                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                              gpu::MemoryUse::DeviceLocal);
  impl->visibleList = gpu::Buffer(device, 2 * (VISIBLE_LIST_HEADER + uint64_t(impl->gpuScene.objectCount)) * 4,
                                  VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                                      VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT,
                                  gpu::MemoryUse::DeviceLocal);
  impl->pyramid.create(device);
  impl->timestamps = std::make_unique<gpu::TimestampPool>(device, 16);
  if (impl->hasPointLights()) {  // scenes without point lights allocate no light buffers at all
    std::vector<gpu::PointLightData> lights;
    for (const PointLight& l : scene.pointLights) {
      const glm::vec2 cone(spotAngleScaleOffset(l));
      lights.push_back({glm::vec4(glm::vec3(l.position - scene.anchor), l.range), glm::vec4(l.color, l.intensity),
                        glm::vec4(l.direction, 0.0f), cone.x, cone.y, uint32_t(l.type), 0u});
    }
    impl->pointLights = gpu::uploadVector(device, lights, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
    impl->lightCull.create(device, impl->pipelineLayout, w);
  }
  impl->createTargets(config.width, config.height);
  const bool gpuBounds = config.skinBounds == SkinBounds::Gpu;
  auto animation = AnimationState::create(device, scene, impl->gpuScene, gpuBounds);
  if (!animation) return animation.error();
  impl->animation = std::move(animation.value());
  if (impl->animation)
    impl->skin.create(device,
                      {vertexWindows(impl->gpuScene.vertices, impl->vertexShift), impl->gpuScene.meshes.handle(),
                       impl->gpuScene.skinVertices.handle(), impl->animation->joints().handle(),
                       impl->animation->instances().handle(), impl->gpuScene.vertexExtras.handle(),
                       impl->animation->bounds().handle(),
                       impl->gpuScene.morphDeltas ? impl->gpuScene.morphDeltas.handle() : impl->animation->joints().handle(),
                       gpuBounds},
                      impl->vertexShift);
  return std::unique_ptr<Renderer>(new Renderer(std::move(impl)));
}

Status Renderer::resize(uint32_t width, uint32_t height) {
  if (width == 0 || height == 0 || width > 16384 || height > 16384)
    return makeError(ErrorCode::InvalidArgument, fmt::format("image size {}x{} outside 1..16384", width, height));
  impl_->createTargets(width, height);
  impl_->pyramidSkipFrames = 0;  // a new size: probe the pyramid again
  return {};  // the draw lists stay valid (they do not depend on the size): freezeCulling still works
}

Result<FrameResult> Renderer::renderFrame(const Camera& camera, const FrameOptions& options) {
  return impl_->render(camera, options);
}

const IdEncoding& Renderer::idEncoding() const { return impl_->encoding; }

Result<SkinnedInstanceReadback> Renderer::readSkinnedInstance(uint32_t instance) const {
  const GpuScene& g = impl_->gpuScene;
  if (instance >= g.skinned.size())
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("skinned instance {}: the scene has {}", instance, g.skinned.size()));
  const GpuScene::SkinnedRegion& r = g.skinned[instance];
  SkinnedInstanceReadback out;
  out.object = r.object;
  gpu::Device& dev = impl_->device;
  std::vector<uint8_t> bytes =
      gpu::downloadBuffer(dev, g.skinnedVertices[r.block], r.vertexBytes, uint64_t(r.vertexCount) * sizeof(gpu::SkinnedVertex));
  out.vertices.resize(r.vertexCount);
  std::memcpy(out.vertices.data(), bytes.data(), bytes.size());
  if (r.tangentBytes) {
    bytes = gpu::downloadBuffer(dev, g.skinnedVertices[r.block], r.tangentBytes, uint64_t(r.vertexCount) * sizeof(uint32_t));
    out.tangents.resize(r.vertexCount);
    std::memcpy(out.tangents.data(), bytes.data(), bytes.size());
  }
  bytes = gpu::downloadBuffer(dev, g.meshes, uint64_t(r.meshSlot) * sizeof(gpu::MeshData), sizeof(gpu::MeshData));
  gpu::MeshData md;
  std::memcpy(&md, bytes.data(), sizeof(md));
  out.bounds = md.boundsSphere;
  return out;
}

void Renderer::clearHistory() {
  impl_->historyDirty = true;
  impl_->pyramidSkipFrames = 0;  // a cut: probe the pyramid again at once
}

}  // namespace visbuf
