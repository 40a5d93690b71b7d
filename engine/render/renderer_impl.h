// Renderer::Impl: the renderer's state (the GPU mirror of the scene, targets, pipelines, descriptor set, per-frame
// resources) shared by the files of engine/render: renderer_setup.cpp (creation, targets, descriptors),
// frame_passes.cpp (recording of each pass), frame_readback.cpp (stats and readback), renderer.cpp (the frame script).
#pragma once

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

namespace {

constexpr VkClearColorValue kBackground{{0.10f, 0.12f, 0.15f, 1.0f}};
constexpr uint32_t kCommandBuffers = 14;  // at most 14: setup, skin, 2 x (cull, raster, micro-raster), pyramid,
                                          // light cull, classify, shade (or G-buffer lighting), transparent, readback
// A pyramid that occluded nothing is skipped for this many frames, then built again to re-probe.
constexpr uint32_t kPyramidProbeInterval = 16;
// Likewise the micro-raster, after a frame in which it took no draw.
constexpr uint32_t kSwProbeInterval = 16;

}  // namespace

std::array<VkDescriptorBufferInfo, VERTEX_WINDOWS> vertexWindows(const gpu::Buffer& pool, uint32_t shift);
bool defaultSwRaster(const gpu::Device& device);
inline constexpr uint64_t kGpuSwMinTriangles = 262144;

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

  void createLayouts();

  void createTargets(uint32_t width, uint32_t height);

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
  void resizeAttributes(VkDeviceSize bytes);

  void writeDescriptors();

  // The G-buffer pipelines and targets at the current size (only renderers that draw the G-buffer baseline pay
  // for them).
  void ensureGBufferTargets();

  // FrameOptions::msaa against the device and the frame's other options (what MSAA does not cover is refused).
  Status checkMsaa(const FrameOptions& o) const;

  // The multisampled targets and pipelines of this frame's sample count (created once per count and size), and
  // the descriptors that the shading and light culling passes read them through.
  void prepareMsaa(const FrameOptions& options);

  // The classification pipelines and buffers (only renderers that shade classified frames pay for them).
  void ensureClassify();
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

  gpu::FrameData frameData(const Camera& camera, const FrameMath& math, const FrameOptions& options) const;

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

}  // namespace visbuf
