// Recording of the frame's passes: the GPU-culled visbuf and G-buffer frames, the G-buffer lighting, the forward
// baseline's CPU culling and the transparency pass.
#include "visbuf/render/renderer_impl.h"

#include <algorithm>

namespace visbuf {

gpu::FrameData Renderer::Impl::frameData(const Camera& camera, const FrameMath& math, const FrameOptions& options,
                                         const FramePlan& plan) const {
  gpu::FrameData f{};
  f.viewProj = glm::mat4(math.viewProj);
  f.view = glm::mat4(math.view);
  f.projX = float(math.proj[0][0]);
  f.projY = float(math.proj[1][1]);
  f.pyramidLevels = plan.usePyramid ? pyramid.levels() : 0;
  f.cameraOffset = glm::vec4(glm::vec3(scene.anchor - camera.position), 0.0f);
  for (int i = 0; i < 5; ++i) f.frustum[i] = glm::vec4(math.planes[size_t(i)]);
  f.lightDir = glm::vec4(glm::normalize(scene.lightDirection), scene.lightIntensity);
  f.pointLightCount = uint32_t(scene.pointLights.size());
  f.lightTilesX = plan.lightsCulled ? lightCull.tilesX() : 0u;
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
  f.swRaster = plan.swOn ? 1u : 0u;
  f.swMaxPixels = options.swRasterPixels;
  f.swTriangleBits = encoding.wide ? 32u - std::min(encoding.slotBits, 31u) : encoding.triangleBits;
  f.swMaxTriangles = encoding.wide ? std::min(1u << f.swTriangleBits, SW_RASTER_MAX_TRIANGLES) : SW_RASTER_MAX_TRIANGLES;
  if (plan.coveredTiles) {
    const VkDeviceAddress a = coveredTiles.address();
    f.coveredTilesLow = uint32_t(a);
    f.coveredTilesHigh = uint32_t(a >> 32);
    f.coveredTilesX = (config.width + SHADE_TILE_X - 1) / SHADE_TILE_X;
  }
  return f;
}

// The "what a user does without us" baseline's per-object test: CPU frustum culling (double precision) and the
// same LOD rule. False: culled. centre: the world bounds centre (transparency sorts by it).
bool Renderer::Impl::cullObject(uint32_t i, const Camera& camera, const FrameMath& math, const FrameOptions& options,
                                FrameStats& st, passes::ForwardDraw& draw, glm::dvec3& centre) const {
  const Object& o = objects[i];
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
  for (uint32_t i = 0; i < objects.size(); ++i) {
    if (gpuScene.objectList[i] == DRAW_LIST_NONE || !isDrawn(i)) continue;
    passes::ForwardDraw d;
    glm::dvec3 centre;
    if (cullObject(i, camera, math, options, st, d, centre)) out.push_back(d);
  }
  if (listMask & ~1u)
    std::stable_sort(out.begin(), out.end(),
                     [](const passes::ForwardDraw& a, const passes::ForwardDraw& b) { return a.list < b.list; });
  st.objectsTested = uint32_t(objects.size());
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
    if (!isDrawn(i)) continue;
    passes::TransparentDraw t;
    glm::dvec3 centre;
    if (!cullObject(i, camera, math, options, mine, t.draw, centre)) continue;
    const Material& m = scene.materials[objects[i].material];
    // Face culling as an opaque object of the same winding and sidedness (a skinned object: its placement's).
    glm::dmat4 placed = objects[i].transform;
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
void Renderer::Impl::recordVisbuf(const FrameOptions& options, const FramePlan& plan, uint32_t& used) {
  const uint32_t w = config.width, h = config.height;
  const bool deferred = options.path == RenderPath::GBuffer;
  const bool frozen = plan.frozen;
  const bool occlusion = plan.cull == CullMode::Occlusion;
  const bool usePyramid = plan.usePyramid;
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
                          VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
                          VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      gpu::imageBarrier(cmd, depthTarget, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                        VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0, kDepthStages, kDepthAccess);
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
  const bool sw = !deferred && plan.swOn;
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

  if (plan.lightsCulled) {  // tile light lists from the final depth
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
  const bool classified = plan.shading == ShadingMode::Classified;
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
                    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0, VK_PIPELINE_STAGE_2_TRANSFER_BIT,
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
  // The shading's own counters (a frozen frame keeps the cull counts, not these): per-sample pixels (MSAA) and
  // covered pixels.
  if (msaa) vkCmdFillBuffer(cmd, stats.handle(), STAT_PER_SAMPLE_PIXELS * sizeof(uint32_t), sizeof(uint32_t), 0);
  vkCmdFillBuffer(cmd, stats.handle(), STAT_COVERED_PIXELS * sizeof(uint32_t), sizeof(uint32_t), 0);
  gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  if (classified)
    classify.recordShade(cmd, pipelineLayout, set);
  else if (plan.coveredTiles)
    shade.recordCovered(cmd, pipelineLayout, set, coveredTiles, w, h);
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
                    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
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

// The forward baseline: CPU culling (one draw per object), then one raster pass into colour and depth.
void Renderer::Impl::recordForward(const Camera& camera, const FrameMath& math, const FrameOptions& options,
                                   FrameStats& st, uint32_t& used, FrameResult* result) {
  const uint32_t w = config.width, h = config.height;
  const bool msaa = options.msaa > 1;
  std::vector<passes::ForwardDraw> fdraws = forwardCull(camera, math, options, st);
  if (options.readDraws && result)
    for (const auto& d : fdraws) {
      const gpu::MeshData& md = gpuScene.meshTable[gpuScene.objectMesh[d.objectId]];
      uint32_t lod = 0;
      while (lod + 1 < md.lodCount && md.lods[lod].firstIndex != d.firstIndex) ++lod;
      result->drawnObjects.push_back(d.objectId);
      result->drawnLods.push_back(lod);
    }
  VkCommandBuffer cmd = cmds[used++];
  beginCmd(cmd);
  // MSAA: multisampled colour + depth, the colour averaged into `color` at the end (hardware resolve).
  const gpu::Image& colorTarget = msaa ? colorMs : color;
  const gpu::Image& depthTarget = msaa ? depthMs : depth;
  gpu::imageBarrier(cmd, color, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  if (msaa)
    gpu::imageBarrier(cmd, colorMs, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                      VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, 0,
                      VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  gpu::imageBarrier(cmd, depthTarget, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
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

}  // namespace visbuf
