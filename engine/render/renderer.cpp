// The frame script: the only place that knows the pass order. Each pass declares what it reads and writes
// (frame_passes.cpp); the frame graph (gpu/frame_graph.h) drops what nothing reads and derives the barriers.
//
//   visbuf:   setup ─► [skin] ─► cull ─► raster ─► [micro-raster ─► merge] ─► shade ─► counters ─► [readback]
//             occlusion: cull early ─► raster early ─► [depth pyramid] ─► cull late ─► raster late (each raster
//             with its micro-raster); [light cull] and [classify] before shade; [transparent] after it
//   G-buffer: the same culling and raster into the G-buffer targets, then lighting
//   forward:  setup ─► [skin] ─► forward (CPU culled) ─► [transparent] ─► counters ─► [readback]
//
// Each pass is recorded into its own command buffer, all submitted at once (Mesa 22.3 lavapipe
// crashed on a dispatch + barrier + timestamps in one command buffer).
#include "visbuf/render/renderer_impl.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include <fmt/format.h>
#include <glm/gtc/packing.hpp>

namespace visbuf {

const char* renderPathName(RenderPath path) {
  return path == RenderPath::Visbuf ? "visbuf" : path == RenderPath::GBuffer ? "gbuffer" : "forward";
}
const char* cullModeName(CullMode mode) {
  return mode == CullMode::None ? "none" : mode == CullMode::Frustum ? "frustum" : "occlusion";
}
const char* shadingModeName(ShadingMode mode) {
  switch (mode) {
    case ShadingMode::Auto: return "auto";
    case ShadingMode::Uber: return "uber";
    case ShadingMode::Classified: return "classified";
    case ShadingMode::Covered: return "covered";
  }
  return "auto";
}
ShadingMode parseShadingMode(const std::string& name) {
  return name == "uber"         ? ShadingMode::Uber
         : name == "classified" ? ShadingMode::Classified
         : name == "covered"    ? ShadingMode::Covered
                                : ShadingMode::Auto;
}
// The benchmark's verdict per device type (docs/benchmarks.md, "Shading only covered pixels" and "Material
// classification"). Classification loses on both (lavapipe: two passes over the IDs cost more than the shading saves;
// H100: many small per-material dispatches shade slower than one divergent dispatch). Covered pixels win on lavapipe,
// where every lane of a SIMD batch runs the whole shader, background or not (an empty 1024x768 frame shaded in 30.4 ms,
// listed 1.2 ms); covered tiles lost a little on the H200, where a background pixel's early exit is free and the
// listing adds ~15 us (0.127 -> 0.144 ms at 10k kittens).
ShadingMode defaultShadingFor(bool cpuDevice) { return cpuDevice ? ShadingMode::Covered : ShadingMode::Uber; }
float defaultSwRasterPixels(bool cpuDevice) { return cpuDevice ? float(SW_RASTER_MAX_EXTENT - 2) : 64.0f; }
static_assert(kMaxSwRasterArea == float(SW_RASTER_MAX_EXTENT * SW_RASTER_MAX_EXTENT));
ShadingMode defaultShading(const gpu::Device& device) { return defaultShadingFor(device.isCpu()); }

const char* swRasterModeName(SwRasterMode mode) {
  return mode == SwRasterMode::Auto ? "auto" : mode == SwRasterMode::On ? "on" : "off";
}
SwRasterMode parseSwRasterMode(const std::string& name) {
  return name == "on" ? SwRasterMode::On : name == "off" ? SwRasterMode::Off : SwRasterMode::Auto;
}

const char* swResolveName(SwResolve mode) {
  return mode == SwResolve::Auto ? "auto" : mode == SwResolve::Merge ? "merge" : "shading";
}
SwResolve parseSwResolve(const std::string& name) {
  return name == "merge" ? SwResolve::Merge : name == "shading" ? SwResolve::Shading : SwResolve::Auto;
}

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

// The checks of a frame's camera and options, and what a frame needs created first (each once: not part of any
// frame's CPU time).
Status Renderer::Impl::prepareFrame(const Camera& camera, const FrameOptions& options) {
  if (Status s = validateCamera(camera); !s) return s;

  if (options.readIds && options.path == RenderPath::GBuffer)
    return makeError(ErrorCode::InvalidArgument, "the G-buffer path writes no IDs (readIds: visbuf or forward)");
  if (options.path == RenderPath::GBuffer) ensureGBufferTargets();
  if (Status s = checkMsaa(options); !s.ok()) return s;
  if (options.swRaster != SwRasterMode::Off && options.swRasterPixels &&
      !(*options.swRasterPixels > 0.0f && *options.swRasterPixels <= SW_RASTER_MAX_EXTENT - 2))
    return makeError(ErrorCode::InvalidArgument, fmt::format("micro-raster size bound {} px outside (0, {}]",
                                                             *options.swRasterPixels, SW_RASTER_MAX_EXTENT - 2));
  if (options.swRaster != SwRasterMode::Off && options.swRasterArea &&
      !(*options.swRasterArea > 0.0f && *options.swRasterArea <= kMaxSwRasterArea))
    return makeError(ErrorCode::InvalidArgument, fmt::format("micro-raster area bound {} px per triangle outside (0, {}]",
                                                             *options.swRasterArea, kMaxSwRasterArea));
  prepareMsaa(options);  // once per sample count (and size)
  if (resolveShading(options, facts()) == ShadingMode::Classified) ensureClassify();
  if (microRasterAllowed(options, facts()) && swRaster.ensureBuffer(device, config.width, config.height))
    writeDescriptors();
  if (microRasterAllowed(options, facts()) && microRasterResolves(options)) shade.createResolve(device, textured);
  const uint32_t w = config.width, h = config.height;
  const bool readAttributes = options.readAttributes && options.path != RenderPath::Forward;
  const VkDeviceSize attributeBytes = VkDeviceSize(w) * h * ATTRIBUTE_FLOATS * sizeof(float);
  // MSAA readIds: the sample-ID copy goes through the attribute buffer (2 uints per sample).
  const VkDeviceSize sampleIdBytes = options.msaa > 1 && options.readIds ? VkDeviceSize(w) * h * options.msaa * 8 : 0;
  if (std::max(readAttributes ? attributeBytes : 0, sampleIdBytes) > attributes.size()) {
    resizeAttributes(std::max(attributeBytes, sampleIdBytes));
    writeDescriptors();
  }
  if (options.readIds && options.path == RenderPath::Forward && !forwardIds)
    forwardIds = gpu::Image(device, VK_FORMAT_R32G32_UINT, w, h,
                            VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_IMAGE_ASPECT_COLOR_BIT);
  if (idsReadback.size() < sampleIdBytes)
    idsReadback = gpu::Buffer(device, sampleIdBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
  return {};
}

// The slot of the next frame: a frame recorded into it earlier has finished (record()'s contract, or renderFrame's
// wait), so its counters are read now.
FrameSlot& Renderer::Impl::beginFrame() {
  FrameSlot& f = slots[frameCounter % slots.size()];
  if (f.pending) {
    collectStats(f, false);
    completed = f.stats;
  }
  sceneSet = sceneSets.set(uint32_t(frameCounter % slots.size()));
  cmds = f.cmds.data();
  timestamps = f.timestamps.get();
  return f;
}

// The frame script: the pass order of every path, declared into the frame graph, which drops the passes whose
// writes nothing reads, derives the barriers and records one command buffer per pass.
uint32_t Renderer::Impl::recordFrame(const Camera& camera, const FrameOptions& options, const FramePlan& plan,
                                     FrameSlot& slot, FrameResult* result, FrameReadback* readback,
                                     const FrameInputs* inputs) {
  const uint32_t w = config.width, h = config.height;
  FrameMath math = computeFrameMath(camera, w, h);
  gpu::FrameData fd = frameData(camera, math, options, plan);
  std::memcpy(slot.frameBuffer.mapped(), &fd, sizeof(fd));

  slot.plan = plan;
  slot.options = options;
  slot.stats = FrameStats{};
  FrameStats& st = slot.stats;
  st.frameIndex = frameCounter;
  st.device = device.name();
  st.path = options.path;
  st.width = w;
  st.height = h;
  st.objects = gpuScene.objectCount;
  st.cull.drawCapacity = capacity;
  st.ids = encoding;
  st.sceneBytes = gpuScene.bytes + (animation ? animation->bytes() : 0);
  st.textureClasses = uint32_t(gpuScene.textureClasses.size());
  st.textureBytes = gpuScene.textureBytes;
  st.texturesDecompressed = gpuScene.texturesDecompressed;
  st.lights.pointLights = uint32_t(scene.pointLights.size());
  st.lights.bytes = hasPointLights() ? pointLights.size() + lightCull.tiles().size() : 0;
  st.lights.culled = plan.lightsCulled;
  st.msaaSamples = options.msaa;
  st.shade.mode = plan.shading;
  st.pyramid.skipped = plan.occlusionFrame && !plan.usePyramid;
  st.cull.cullingFrozen = plan.frozen;
  st.pyramid.levels = plan.usePyramid ? pyramid.levels() : 0;

  Graph g;
  const FrameResources r = declareResources(g, options, plan);
  poseRigidObjects(options.animationTime);
  declareSetup(g, r, options, plan, slot);
  if (animation) {  // skinning: only when the pose changed (a static scene has no AnimationState at all)
    st.skin.instances = animation->instanceCount();
    st.skin.vertices = animation->vertexCount();
    st.skin.bounds = skinBoundsName(config.skinBounds);
    if (animation->update(options.animationTime)) {
      st.skin.ran = true;
      st.skin.animationCpuMs = animation->lastUpdateMs();
      declareSkin(g, r);
    }
  }
  if (plan.gpuCulled) {
    // Culling and raster: each raster phase followed by the micro-raster's, when it takes draws this frame.
    const bool deferred = options.path == RenderPath::GBuffer, occlusion = plan.cull == CullMode::Occlusion;
    auto rasterPhase = [&](uint32_t phase, bool clear, const char* name) {
      declareRaster(g, r, options, plan, phase, clear, name);
      if (plan.swOn && !deferred) declareMicroRaster(g, r, phase, clear, !plan.swResolved);
    };
    const char* rasterOnly = deferred ? "gbuffer" : "visibility";
    const char* rasterEarly = deferred ? "gbuffer early" : "raster early";
    const char* rasterLate = deferred ? "gbuffer late" : "raster late";
    if (plan.frozen) {  // the draw lists and their counts are the frozen frame's: raster them as they are
      rasterPhase(CULL_PHASE_EARLY, true, occlusion ? rasterEarly : rasterOnly);
      if (occlusion) rasterPhase(CULL_PHASE_LATE, false, rasterLate);
    } else if (!occlusion) {
      declareCull(g, r, plan, CULL_PHASE_EARLY, "cull");
      rasterPhase(CULL_PHASE_EARLY, true, rasterOnly);
    } else if (plan.lateOnly) {  // no pyramid this frame: the late phase over every object, alone
      declareCull(g, r, plan, CULL_PHASE_LATE, "cull");
      rasterPhase(CULL_PHASE_LATE, true, rasterOnly);
    } else {
      declareCull(g, r, plan, CULL_PHASE_EARLY, "cull early");
      rasterPhase(CULL_PHASE_EARLY, true, rasterEarly);
      // (dropped when the late cull does not test against it)
      declarePyramid(g, r, plan.msaa, options.readPyramid, plan.swResolved);
      declareCull(g, r, plan, CULL_PHASE_LATE, "cull late");
      rasterPhase(CULL_PHASE_LATE, false, rasterLate);
    }
    if (deferred) {
      declareGBufferLighting(g, r, options.readAttributes);
    } else {
      if (hasPointLights()) declareLightCull(g, r, plan.msaa);  // dropped unless the shading reads its tiles
      if (plan.shading == ShadingMode::Classified) declareClassify(g, r);
      declareShade(g, r, options, plan);
      if (plan.msaa && options.readIds) declareSampleIds(g, r);
    }
    st.rasterBytesPerFragment =
        (deferred ? gbuffer.formats.bytesPerPixel() : gpu::formatBytes(ids.format())) + 4 /*depth*/;
    st.targetBytesPerPixel = st.rasterBytesPerFragment * options.msaa + 8 /*colour*/;  // raster targets per sample
  } else {
    declareForward(g, r, camera, math, options, st, result);
  }
  if (!blendObjects.empty()) declareTransparent(g, r, camera, math, options, st);
  frameHistory.recorded(plan);
  declareCounters(g, r, slot);
  if (readback) declareReadback(g, r, options, plan, *readback);

  // What the frame hands on: the colour, depth and (visbuf) IDs, in the layouts record() states.
  constexpr VkPipelineStageFlags2 all = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  const VkImageLayout colorLayout = inputs ? inputs->colorLayout : VK_IMAGE_LAYOUT_UNDEFINED;  // (kept as it is)
  const VkImageLayout sampled = inputs ? VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL : VK_IMAGE_LAYOUT_UNDEFINED;
  g.output(r.color, {all, VK_ACCESS_2_MEMORY_READ_BIT, colorLayout});
  g.output(r.depth, {all, VK_ACCESS_2_MEMORY_READ_BIT, sampled});
  if (options.path == RenderPath::Visbuf) g.output(r.ids, {all, VK_ACCESS_2_MEMORY_READ_BIT, sampled});

  const Graph::Report report =
      g.record(std::span<const VkCommandBuffer>(cmds, kCommandBuffers), [this](VkCommandBuffer c) { beginCmd(c); },
               timestamps);
  st.graph.passesRecorded = report.recorded;
  st.graph.passesDropped = report.dropped;
  st.graph.barriers = report.barriers;
  st.graph.layoutTransitions = report.layoutTransitions;
  ++frameCounter;
  return uint32_t(report.recorded.size());
}

Result<FrameResult> Renderer::Impl::render(const Camera& camera, const FrameOptions& options) {
  using Clock = std::chrono::steady_clock;
  if (Status s = prepareFrame(camera, options); !s.ok()) return s.error();
  const auto t0 = Clock::now();
  FrameSlot& slot = beginFrame();
  const FramePlan plan = planFrame(options, facts(), frameHistory);
  FrameResult result;
  FrameReadback rb;
  rb.attributes = plan.readAttributes;
  rb.attributeBytes = VkDeviceSize(config.width) * config.height * ATTRIBUTE_FLOATS * sizeof(float);
  rb.sampleIdBytes = plan.msaa && options.readIds ? VkDeviceSize(config.width) * config.height * options.msaa * 8 : 0;
  const uint32_t used = recordFrame(camera, options, plan, slot, &result, &rb, nullptr);

  const auto t1 = Clock::now();
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = used;
  si.pCommandBuffers = cmds;
  VK_CHECK(vkResetFences(device.device(), 1, &fence));
  VK_CHECK(vkQueueSubmit(device.queue(), 1, &si, fence));
  VK_CHECK_WAIT(vkWaitForFences(device.device(), 1, &fence, VK_TRUE, UINT64_MAX), device.queue());

  collectStats(slot, true);
  completed = slot.stats;
  result.stats = slot.stats;
  decodeReadback(options, plan, rb, slot, result);
  const auto t3 = Clock::now();
  result.stats.cpuRecordMs = std::chrono::duration<double, std::milli>(t1 - t0).count();
  result.stats.wallMs = std::chrono::duration<double, std::milli>(t3 - t1).count();
  return result;
}

// record(): the frame for the host to submit, its outputs published by the last command buffer.
Result<RecordedFrame> Renderer::Impl::record(const FrameInputs& inputs) {
  const FrameOptions& options = inputs.options;
  if (options.readColor || options.readIds || options.readDraws || options.readPyramid || options.readAttributes ||
      options.countOverdraw)
    return makeError(ErrorCode::InvalidArgument,
                     "record(): read*, countOverdraw are renderFrame's (it reads back); clear them for record()");
  if (inputs.colorLayout != VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL &&
      inputs.colorLayout != VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL && inputs.colorLayout != VK_IMAGE_LAYOUT_GENERAL)
    return makeError(ErrorCode::InvalidArgument,
                     "record(): colorLayout must be TRANSFER_SRC_OPTIMAL, SHADER_READ_ONLY_OPTIMAL or GENERAL");
  if (Status s = prepareFrame(inputs.camera, options); !s.ok()) return s.error();
  FrameSlot& slot = beginFrame();
  // Skinned scenes: the joint and instance buffers are single, so a new pose waits for the frames still queued.
  if (animation && animation->wouldUpdate(options.animationTime) && slots.size() > 1) vkDeviceWaitIdle(device.device());
  const FramePlan plan = planFrame(options, facts(), frameHistory, /*handsOn=*/true);
  RecordedFrame out;
  out.index = frameCounter;
  const uint32_t used = recordFrame(inputs.camera, options, plan, slot, nullptr, nullptr, &inputs);
  describeOutputs(plan, inputs, out);
  slot.pending = true;
  out.commandBuffers.assign(cmds, cmds + used);
  return out;
}

// The outputs and their final layouts: colour as asked, IDs and depth sampled (SHADER_READ_ONLY_OPTIMAL); the frame
// graph leaves every write to them available and visible to any later command.
void Renderer::Impl::describeOutputs(const FramePlan& plan, const FrameInputs& inputs, RecordedFrame& out) const {
  const FrameOptions& options = inputs.options;
  const gpu::Image& idTarget = plan.msaa ? idsMs : ids;
  const gpu::Image& depthTarget = options.path == RenderPath::GBuffer ? depth : plan.msaa ? depthMs : depth;
  out.width = config.width;
  out.height = config.height;
  out.color = {color.handle(), color.view(), color.format(), inputs.colorLayout};
  out.depth = {depthTarget.handle(), depthTarget.view(), depthTarget.format(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  if (options.path == RenderPath::Visbuf)
    out.ids = {idTarget.handle(), idTarget.view(), idTarget.format(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
}

Result<FrameResult> Renderer::renderFrame(const Camera& camera, const FrameOptions& options) {
  return impl_->guarded([&] { return impl_->render(camera, options); });
}

Result<RecordedFrame> Renderer::record(const FrameInputs& inputs) {
  return impl_->guarded([&] { return impl_->record(inputs); });
}

bool Renderer::lost() const { return impl_->failure.has_value(); }

const std::optional<FrameStats>& Renderer::completedStats() const { return impl_->completed; }

const IdEncoding& Renderer::idEncoding() const { return impl_->encoding; }

Result<SkinnedInstanceReadback> Renderer::readSkinnedInstance(uint32_t instance) const {
  return impl_->guarded([&]() -> Result<SkinnedInstanceReadback> {
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
  });
}

void Renderer::clearHistory() {
  impl_->historyDirty = true;
  impl_->frameHistory.cut();  // a cut: probe the pyramid again at once
}

}  // namespace visbuf
