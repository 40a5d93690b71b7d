// Renderer::Impl: the renderer's state (the GPU mirror of the scene, targets, pipelines, descriptor set, per-frame
// resources) shared by the files of engine/render: renderer_setup.cpp (creation, targets, descriptors),
// frame_passes.cpp (recording of each pass), frame_readback.cpp (stats and readback), renderer.cpp (the frame script).
#pragma once

#include "visbuf/render/renderer.h"

#include <optional>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <glm/gtc/packing.hpp>

#include "visbuf/core/log.h"
#include "visbuf/gpu/check.h"
#include "visbuf/gpu/frame_graph.h"
#include "visbuf/gpu/pipeline.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/passes/classify_pass.h"
#include "visbuf/passes/cull_pass.h"
#include "visbuf/passes/depth_pyramid_pass.h"
#include "visbuf/passes/forward_pass.h"
#include "visbuf/passes/gbuffer_lighting_pass.h"
#include "visbuf/passes/gbuffer_pass.h"
#include "visbuf/passes/light_cull_pass.h"
#include "visbuf/passes/object_upload_pass.h"
#include "visbuf/passes/shade_pass.h"
#include "visbuf/passes/skin_pass.h"
#include "visbuf/passes/sw_raster_pass.h"
#include "visbuf/passes/transparent_pass.h"
#include "visbuf/render/animation_state.h"
#include "visbuf/passes/visibility_pass.h"
#include "visbuf/render/frame_math.h"
#include "visbuf/render/frame_plan.h"
#include "visbuf/render/scene_descriptors.h"
#include "visbuf/scene/gpu_scene.h"

namespace visbuf {

namespace {

constexpr VkClearColorValue kBackground{{kBackgroundColor[0], kBackgroundColor[1], kBackgroundColor[2], kBackgroundColor[3]}};
// The covered-pixel list's words at a target size: its header, then one per pixel (covered_pixels.comp).
constexpr VkDeviceSize coveredListWords(uint32_t width, uint32_t height) {
  return COVERED_PIXELS_HEADER + VkDeviceSize(width) * height;
}
constexpr uint32_t kCommandBuffers = 20;  // one per recorded pass, at most 18: setup, skin, 2 x (cull, raster,
                                          // micro-raster, merge), pyramid, light cull, classify, shade (or G-buffer
                                          // lighting), sample IDs, transparent, counters, readback

}  // namespace

using Graph = gpu::FrameGraph;
namespace access = gpu::access;

// The resources of one frame's graph (declared by Renderer::Impl::declareResources): the buffers by what they hold,
// the images this frame renders into (the multisampled ones with MSAA).
struct FrameResources {
  static constexpr Graph::Resource kNone = Graph::kNoResource;  // (not declared this frame)
  Graph::Resource scene = kNone, stats = kNone, draws = kNone, history = kNone, sw = kNone, lightTiles = kNone,
                  classification = kNone, coveredPixels = kNone, attributes = kNone;
  Graph::Resource ids = kNone, depth = kNone, color = kNone, colorMs = kNone, forwardIds = kNone, pyramid = kNone,
                  overdraw = kNone;
  std::array<Graph::Resource, GBUFFER_TARGETS> gbuffer = [] {
    std::array<Graph::Resource, GBUFFER_TARGETS> a;
    a.fill(kNone);
    return a;
  }();
};

// What renderFrame reads back (frame_readback.cpp).
struct FrameReadback {
  bool draws = false, pyramid = false, attributes = false;
  VkDeviceSize attributeBytes = 0, sampleIdBytes = 0;
  std::vector<std::pair<uint32_t, uint32_t>> pyramidSizes;
};

// Per-frame resources: a ring of RendererConfig::framesInFlight slots. Frame n uses slot n % framesInFlight.
struct FrameSlot {
  gpu::Buffer frameBuffer;               // FrameData, host visible (the slot's scene set: SCENE_BINDING_FRAME)
  gpu::Buffer statsReadback;             // the counters, copied at the end of the frame
  gpu::Buffer staging;                   // object records the frame uploads, host visible (grown on demand)
  std::unique_ptr<gpu::TimestampPool> timestamps;
  std::array<VkCommandBuffer, kCommandBuffers> cmds{};
  bool pending = false;  // recorded by record(): its counters are read when the slot comes round again
  FramePlan plan;
  FrameOptions options;
  FrameStats stats;      // what recording knew; completed from the counters (Renderer::Impl::collectStats)
};

struct Renderer::Impl {
  gpu::Device& device;
  const Scene& scene;
  RendererConfig config;
  GpuScene gpuScene;
  IdEncoding encoding;
  uint32_t capacity = 0;      // draws per phase (all draw lists together): draws[0, capacity) early, then late
  // Draw lists (config.h DRAW_LIST_*): list l holds slots [listFirst[l], + listCapacity[l]) of each phase's region;
  // capacity 0 for a list no object of the scene is in. Mirrored in drawLists (read by the cull pass).
  std::array<uint32_t, DRAW_LISTS> listFirst{}, listCapacity{};
  // The part of list l's capacity reserved for cluster draws (config.h CULL_CLUSTERS); the rest holds one draw per
  // object (listObjectCapacity).
  std::array<uint32_t, DRAW_LISTS> listClusterReserve{};
  uint32_t listObjectCapacity(uint32_t l) const { return listCapacity[l] - listClusterReserve[l]; }
  uint32_t listMask = 0;                 // bit l: listCapacity[l] > 0
  uint32_t swListMask = 0;               // bit l: the micro-raster may take list l's draws (opaque, uncapped)
  std::vector<uint32_t> blendObjects;    // objects with BLEND materials (the transparency pass), scene order
  gpu::Buffer drawLists;
  uint32_t objectSplit = 0;  // first object of the second descriptor window (objectWindowSplit)
  uint32_t vertexShift = 0;  // vertices per vertex-pool window: 1 << vertexShift (vertexWindowShift)

  SceneDescriptors sceneSets;  // set 0 of every pass, one per slot (each pass owns its set 1)
  VkSampler sampler = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;  // renderFrame's own wait
  std::vector<FrameSlot> slots;
  uint64_t frameCounter = 0;             // frames recorded so far (renderFrame and record)
  std::optional<FrameStats> completed;   // the newest collected frame's stats (record())
  // The frame being recorded: its slot's scene set, command buffers and timestamps (beginFrame).
  VkDescriptorSet sceneSet = VK_NULL_HANDLE;
  VkCommandBuffer* cmds = nullptr;
  gpu::TimestampPool* timestamps = nullptr;

  // The scene as the renderer holds it: Scene::objects, then RendererConfig::spareObjects free slots
  // (scene_updates.cpp). Object IDs index these; the GPU records follow with the next frame.
  std::vector<Object> objects;
  enum SlotState : uint8_t { SlotFree = 0, SlotLive = 1, SlotHidden = 2 };
  std::vector<uint8_t> slotState;
  std::vector<uint32_t> freeSlots;      // free IDs, the lowest last (reused first)
  std::vector<uint32_t> dirty;          // IDs whose GPU record the next frame uploads
  std::vector<gpu::ObjectData> dirtyRecords;  // their records, packed when the change was made (parallel to dirty)
  std::vector<uint32_t> dirtyIndex;     // per ID: 1 + its index in `dirty`, 0 when not there
  std::array<uint32_t, DRAW_LISTS> listLive{};  // live objects per draw list (room for addObject / list changes)
  std::vector<uint8_t> skinnedObject;   // per ID: a skinned instance (its pose places it: not movable)
  std::vector<uint8_t> rigidObject;     // per ID: posed by a Scene::rigidObjects clip (until removed)
  double rigidTime = 0.0;               // the animation time rigid objects were last posed at
  bool rigidPosed = false;
  bool isLive(uint32_t id) const { return id < slotState.size() && slotState[id] != SlotFree; }
  bool isDrawn(uint32_t id) const { return id < slotState.size() && slotState[id] == SlotLive; }
  // Queues the GPU record of `id` for the next frame: objectRecord(id), or `record` where the caller packed it (a
  // later change of the same object in the same frame replaces it).
  void markDirty(uint32_t id);
  void markDirty(uint32_t id, const gpu::ObjectData& record);
  // Writes the dirty records into the slot's staging buffer and records their copies (setup command buffer).
  void recordObjectUploads(VkCommandBuffer cmd, FrameSlot& slot, FrameStats& st);
  gpu::ObjectData objectRecord(uint32_t id) const;
  Status checkTransform(uint32_t id, const glm::dmat4& m, const char* what) const;
  // Poses the scene's rigid (node-animated) objects at `time` when it differs from the last posed time: each
  // changed transform is rewritten on the CPU and marked dirty (so uploaded with the frame's other changes). A pose
  // that is singular or non-finite (a clip scaling to zero) keeps the object's previous transform; so does a
  // winding flip into a micro-raster list without room.
  void poseRigidObjects(double time);

  passes::ObjectUploadPass objectUpload;  // scene changes (scene_updates.cpp)
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
  // Point lights (scenes with any): anchor-relative records and the tile lists. Empty otherwise.
  gpu::Buffer pointLights;
  passes::LightCullPass lightCull;
  bool hasPointLights() const { return !scene.pointLights.empty(); }
  // The lights and tile lists the passes' sets hold: with no point lights nothing is allocated and the stats buffer
  // stands in (never read: FrameData.pointLightCount = 0; lavapipe reads every descriptor of a bound set).
  const gpu::Buffer& boundLights() const { return hasPointLights() ? pointLights : stats; }
  const gpu::Buffer& boundLightTiles() const { return hasPointLights() ? lightCull.tiles() : stats; }
  gpu::Buffer history;      // uint per object: visible at the end of the last occlusion-culled frame
  gpu::Buffer visibleList;  // the same set listed (config.h VISIBLE_LIST_HEADER): the early cull's threads
  bool historyDirty = true; // cleared before the next frame (creation, clearHistory)
  // The first Vulkan failure of a public call (a VulkanFailure thrown by VK_CHECK): from then on the renderer is
  // lost and every call that would touch the GPU returns lostError().
  std::optional<Error> failure;
  Error lostError() const {
    return makeError(failure->code, "the renderer is unusable after an earlier failure (" + failure->message +
                                        "): destroy it and create another");
  }
  // A public method's body: refused once the renderer is lost; a VulkanFailure inside marks it lost, is logged and
  // comes back as its error (out of memory, device lost, or another Vulkan error).
  template <class F>
  auto guarded(F&& f) -> decltype(f()) {
    if (failure) return lostError();
    try {
      return f();
    } catch (const gpu::VulkanFailure& e) {
      failure = gpu::errorOf(e);
      logMessage(LogLevel::Error, "renderer: " + failure->message + "; the renderer is lost");
      return *failure;
    }
  }
  gpu::Buffer pyramidReadback;
  gpu::Buffer overdrawReadback;
  gpu::Buffer attributes;           // float[ATTRIBUTE_FLOATS] per pixel; a 64-byte placeholder until asked for
  gpu::Buffer attributesReadback;

  gpu::Buffer draws;        // DrawCommand[capacity]
  gpu::BufferView drawTexels;  // the same as R32UI texels: the shading's per-pixel fetch
  gpu::Buffer stats;        // uint[STAT_COUNT]
  gpu::Image ids, depth, color;
  gpu::Buffer coveredPixels;  // covered-pixel shading: COVERED_PIXELS_HEADER uints + one per pixel
  gpu::BufferView coveredTexels;  // the same as R32UI texels (read so where the frame shaders use texel views)
  // MSAA (FrameOptions::msaa > 1): multisampled IDs and depth (visbuf, forward shares the depth) and forward
  // colour, created by the first frame at a count (msaaSamples) and dropped by a resize; the single-sample ids and
  // depth above stay allocated (the descriptor set's stand-ins). Pipelines for that count likewise.
  uint32_t msaaSamples = 0;  // sample count of idsMs / depthMs (0: none)
  gpu::Image idsMs, depthMs, colorMs;
  passes::VisibilityPass visibilityMs;
  passes::ForwardPass forwardMs;
  uint32_t visibilityMsSamples = 0, forwardMsSamples = 0;
  bool descriptorsMsaa = false;  // the shading's IDs and the light culling's depth are the multisampled views
  std::vector<uint32_t> msaaCounts;  // supportedMsaaSamples(device)
  gpu::Image overdraw;    // r32ui, GENERAL: raster writes per pixel (countOverdraw)
  gpu::Image forwardIds;  // forward path with readIds only (rg32ui: object + 1, triangle); lazily created
  gpu::Buffer colorReadback, idsReadback, drawsReadback;

  Impl(gpu::Device& d, const Scene& s) : device(d), scene(s) {}
  ~Impl() {
    VkDevice dev = device.device();
    vkDeviceWaitIdle(dev);
    for (FrameSlot& f : slots)
      if (f.cmds[0]) vkFreeCommandBuffers(dev, device.commandPool(), kCommandBuffers, f.cmds.data());
    vkDestroyFence(dev, fence, nullptr);
    vkDestroySampler(dev, sampler, nullptr);
  }

  void createLayouts();

  void createTargets(uint32_t width, uint32_t height);

  // An empty visible list (no thread in the next early cull) with its dispatch arguments (0, 1, 1).
  // Byte offset of the late cull's refinement list in the visibleList buffer (config.h VISIBLE_LIST_HEADER).
  VkDeviceSize refineListOffset() const { return (VISIBLE_LIST_HEADER + VkDeviceSize(gpuScene.objectCount)) * 4; }
  // Byte offset of the late phase's list of the objects inside the frustum (config.h LATE_LIST_WORD).
  VkDeviceSize lateListOffset() const {
    return (2 * (VISIBLE_LIST_HEADER + VkDeviceSize(gpuScene.objectCount)) + 2 * VkDeviceSize(gpuScene.objectCount)) * 4;
  }
  // Byte offset of the late phase's list of the objects to draw late (config.h LATE_DRAW_LIST_WORD).
  VkDeviceSize lateDrawListOffset() const { return LATE_DRAW_LIST_WORD(VkDeviceSize(gpuScene.objectCount)) * 4; }
  // Empties the visible list, the refinement list, the late list and the late draw list (count 0, dispatch size
  // 0 x 1 x 1).
  void resetVisibleList(VkCommandBuffer cmd) const {
    const uint32_t header[VISIBLE_LIST_HEADER] = {0, 0, 1, 1};
    for (VkDeviceSize offset : {VkDeviceSize(0), refineListOffset(), lateListOffset(), lateDrawListOffset()})
      vkCmdUpdateBuffer(cmd, visibleList.handle(), offset, sizeof(header), header);
  }

  // The LOD level a draw command of the cull pass draws (whole, or a cluster run within it).
  uint32_t drawLod(const gpu::DrawCommand& d) const {
    const gpu::MeshData& md = gpuScene.meshTable[gpuScene.objectMesh[d.firstInstance]];
    uint32_t lod = 0;
    while (lod + 1 < md.lodCount &&
           !(d.firstIndex >= md.lods[lod].firstIndex && d.firstIndex < md.lods[lod].firstIndex + md.lods[lod].indexCount))
      ++lod;
    return lod;
  }

  // The attribute buffer is only as large as asked for (a full-screen one is 64 bytes per pixel).
  void resizeAttributes(VkDeviceSize bytes);

  // Every set (scene and pass sets) from the current resources; the device goes idle first (only lazily created
  // resources and resizes get here, never a steady frame).
  void writeDescriptors();
  void bindPasses();  // each created pass's own set

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
  // What the frame plans depend on, from the scene, the device and the size (frame_plan.h).
  SceneFacts facts() const {
    return {device.isCpu(), swListMask != 0,
            VkDeviceSize(config.width) * config.height * 8 <= device.properties().limits.maxStorageBufferRange &&
                VkDeviceSize(config.width) * config.height <= device.properties().limits.maxTexelBufferElements,
            hasPointLights(),
            std::any_of(listClusterReserve.begin(), listClusterReserve.end(), [](uint32_t r) { return r > 0; }),
            !blendObjects.empty(),
            textured.texels == 0u || coveredListWords(config.width, config.height) <=
                                         device.properties().limits.maxTexelBufferElements};
  }
  FrameHistory frameHistory;  // what earlier frames left that later plans depend on

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

  gpu::FrameData frameData(const Camera& camera, const FrameMath& math, const FrameOptions& options,
                           const FramePlan& plan) const;
  // Checks the camera and the options against the scene and device; creates what the frame needs lazily.
  Status prepareFrame(const Camera& camera, const FrameOptions& options);
  // The frame script: declares the frame's passes in order into a graph and records it into the slot's command
  // buffers (returns how many). readback (renderFrame) or inputs (record()): what the frame hands on.
  uint32_t recordFrame(const Camera& camera, const FrameOptions& options, const FramePlan& plan, FrameSlot& slot,
                       FrameResult* result, FrameReadback* readback, const FrameInputs* inputs);
  // Fills the counters and GPU times of a finished frame into slot.stats and updates the history decisions.
  void collectStats(FrameSlot& slot, bool synchronous);
  void decodeReadback(const FrameOptions& options, const FramePlan& plan, const FrameReadback& rb,
                      const FrameSlot& frame, FrameResult& result);
  // record(): the output images and the layouts the frame leaves them in.
  void describeOutputs(const FramePlan& plan, const FrameInputs& inputs, RecordedFrame& out) const;
  Result<RecordedFrame> record(const FrameInputs& inputs);
  FrameSlot& beginFrame();
  void writeDescriptorSet(const FrameSlot& slot);

  // Draws of list l in a phase that went to the micro-raster: the end of the list's region.
  uint32_t listSwDrawn(const uint32_t* s, uint32_t phase, uint32_t list) const {
    return (swListMask >> list & 1u) ? std::min(s[STAT_SW_DRAWS + phase * DRAW_LISTS + list], listCapacity[list]) : 0u;
  }

  Result<FrameResult> render(const Camera& camera, const FrameOptions& options);
  // The passes as the frame graph sees them (frame_passes.cpp, frame_readback.cpp): what each reads and writes,
  // and what it records.
  FrameResources declareResources(Graph& g, const FrameOptions& options, const FramePlan& plan) const;
  void declareSetup(Graph& g, const FrameResources& r, const FrameOptions& options, const FramePlan& plan,
                    FrameSlot& slot);
  void declareSkin(Graph& g, const FrameResources& r);
  void declareCull(Graph& g, const FrameResources& r, const FramePlan& plan, uint32_t phase, const char* name);
  void declareRaster(Graph& g, const FrameResources& r, const FrameOptions& options, const FramePlan& plan,
                     uint32_t phase, bool clear, const char* name);
  void declareMicroRaster(Graph& g, const FrameResources& r, uint32_t phase, bool clear, bool merge);
  // (level 0: read back; microRaster: the micro-raster was not merged, and the pyramid reads its buffer too)
  void declarePyramid(Graph& g, const FrameResources& r, bool msaa, bool writeLevel0, bool microRaster);
  void declareLightCull(Graph& g, const FrameResources& r, bool msaa);
  void declareClassify(Graph& g, const FrameResources& r);
  void declareShade(Graph& g, const FrameResources& r, const FrameOptions& options, const FramePlan& plan);
  void declareSampleIds(Graph& g, const FrameResources& r);
  void declareGBufferLighting(Graph& g, const FrameResources& r, bool writeAttributes);
  void declareForward(Graph& g, const FrameResources& r, const Camera& camera, const FrameMath& math,
                      const FrameOptions& options, FrameStats& st, FrameResult* result);
  void declareTransparent(Graph& g, const FrameResources& r, const Camera& camera, const FrameMath& math,
                          const FrameOptions& options, FrameStats& st);
  void declareCounters(Graph& g, const FrameResources& r, FrameSlot& slot);
  void declareReadback(Graph& g, const FrameResources& r, const FrameOptions& options, const FramePlan& plan,
                       FrameReadback& rb);
  std::vector<passes::VisibilityList> phaseLists(uint32_t phase) const;
  std::vector<passes::ForwardDraw> forwardCull(const Camera& camera, const FrameMath& math,
                                               const FrameOptions& options, FrameStats& stats) const;
  bool cullObject(uint32_t i, const Camera& camera, const FrameMath& math, const FrameOptions& options, FrameStats& st,
                  passes::ForwardDraw& draw, glm::dvec3& centre) const;
  std::vector<passes::TransparentDraw> transparentCull(const Camera& camera, const FrameMath& math,
                                                       const FrameOptions& options, FrameStats& st) const;
  // Slots of the draw buffer: [0, capacity) early (or only) phase, [capacity, 2 capacity) late; within a phase
  // the draw lists' regions. Draws a phase actually wrote: min(count, capacity) per list.
  uint32_t listDrawn(const uint32_t* s, uint32_t phase, uint32_t list) const {
    return std::min(s[STAT_LIST_DRAWS + phase * DRAW_LISTS + list], listCapacity[list]);
  }
};

}  // namespace visbuf
