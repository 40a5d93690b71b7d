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
