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
  f.farPlane = glm::vec4(math.planes[5]);
  f.projection = glm::vec4(float(math.proj[2][2]), float(math.proj[3][2]), math.orthographic ? 1.0f : 0.0f,
                           std::isfinite(camera.farPlane) ? float(camera.farPlane) : 0.0f);
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
  f.swMaxPixels = options.swRasterPixels.value_or(defaultSwRasterPixels(facts().cpuDevice));
  f.swMaxAreaPerTriangle = options.swRasterArea.value_or(kDefaultSwRasterArea);
  f.swTriangleBits = encoding.wide ? 32u - std::min(encoding.slotBits, 31u) : encoding.triangleBits;
  f.swMaxTriangles = encoding.wide ? std::min(1u << f.swTriangleBits, SW_RASTER_MAX_TRIANGLES) : SW_RASTER_MAX_TRIANGLES;
  f.clusterCull = plan.clusters ? 1u : 0u;
  f.earlyClusterOcclusion = plan.earlyClusterOcclusion ? 1u : 0u;
  if (plan.coveredPixels) {
    const VkDeviceAddress a = coveredPixels.address();
    f.coveredPixelsLow = uint32_t(a);
    f.coveredPixelsHigh = uint32_t(a >> 32);
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
    ++st.cull.frustumCulled;
    return false;
  }
  double dist = glm::length(glm::dvec3(s) - camera.position) - s.w;
  uint32_t lod = selectLod(mesh, scale, dist, math, camera.nearPlane, options.lodErrorPixels);
  const gpu::MeshData& md = gpuScene.meshTable[gpuScene.objectMesh[i]];
  draw = {md.lods[lod].indexCount, md.lods[lod].firstIndex, int32_t(md.vertexOffset), i, gpuScene.objectList[i]};
  st.trianglesDrawn += md.lods[lod].indexCount / 3;
  st.cull.lodHistogram[lod]++;
  return true;
}

std::vector<passes::ForwardDraw> Renderer::Impl::forwardCull(const Camera& camera, const FrameMath& math,
                                                             const FrameOptions& options, FrameStats& st) const {
  // One draw per object, grouped by draw list (opaque first, as the visibility pass draws them); BLEND objects
  // are the transparency pass's.
  std::vector<passes::ForwardDraw> out;
  st.cull.lodHistogram.assign(MAX_LODS, 0);
  for (uint32_t i = 0; i < objects.size(); ++i) {
    if (gpuScene.objectList[i] == DRAW_LIST_NONE || !isDrawn(i)) continue;
    passes::ForwardDraw d;
    glm::dvec3 centre;
    if (cullObject(i, camera, math, options, st, d, centre)) out.push_back(d);
  }
  if (listMask & ~1u)
    std::stable_sort(out.begin(), out.end(),
                     [](const passes::ForwardDraw& a, const passes::ForwardDraw& b) { return a.list < b.list; });
  st.cull.objectsTested = uint32_t(objects.size());
  st.cull.drawsAppended = st.cull.drawsRendered = uint32_t(out.size());
  return out;
}

std::vector<passes::TransparentDraw> Renderer::Impl::transparentCull(const Camera& camera, const FrameMath& math,
                                                                     const FrameOptions& options,
                                                                     FrameStats& st) const {
  // Culled like the forward path's objects (they are not in the GPU's draw lists), then sorted back to front.
  std::vector<passes::TransparentDraw> out;
  FrameStats mine;  // (their triangles and LODs are reported apart from the opaque draws')
  mine.cull.lodHistogram.assign(MAX_LODS, 0);
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
  st.transparent.draws = uint32_t(out.size());
  st.transparent.triangles = mine.trianglesDrawn;
  return out;
}

// Each pass of the frame as the graph sees it: what it reads and writes (stages, accesses, layouts) and what it
// records. The frame script (renderer.cpp) declares them in order; the graph derives the barriers between them.

FrameResources Renderer::Impl::declareResources(Graph& g, const FrameOptions& options, const FramePlan& plan) const {
  FrameResources r;
  const bool msaa = plan.msaa, deferred = options.path == RenderPath::GBuffer;
  // Buffer-like state (several buffers may share one name: the scene is its records, meshes and vertices).
  r.scene = g.buffer("scene", /*persistent=*/true);  // uploads and skinning: later frames draw what they wrote
  r.stats = g.buffer("counters", /*persistent=*/true);  // a frozen frame redraws with the counts it keeps
  r.draws = g.buffer("draws", /*persistent=*/true);     // ... and the draw lists
  r.history = g.buffer("visible lists", /*persistent=*/true);  // occlusion history for the next frame
  r.sw = g.buffer("micro-raster buffer");
  r.lightTiles = g.buffer("light tiles");
  r.classification = g.buffer("material tiles");
  r.coveredPixels = g.buffer("covered pixels");
  r.attributes = g.buffer("attributes");
  // Images: the raster targets of this frame (multisampled ones with MSAA), their content not needed at the start.
  r.ids = g.image("ids", msaa ? idsMs : ids);
  r.depth = g.image("depth", msaa && !deferred ? depthMs : depth);
  r.color = g.image("color", color);
  if (msaa && options.path == RenderPath::Forward) r.colorMs = g.image("color (multisampled)", colorMs);
  if (forwardIds) r.forwardIds = g.image("forward ids", forwardIds);
  if (deferred)
    for (uint32_t i = 0; i < GBUFFER_TARGETS; ++i) r.gbuffer[i] = g.image(fmt::format("gbuffer {}", i), gbufferTargets[i]);
  // Kept from frame to frame in GENERAL: the pyramid (zero-filled at creation: a valid, conservative pyramid for
  // a frame that reads it before any build) and the overdraw counter image.
  r.pyramid = g.image("depth pyramid", pyramid.pyramid(), VK_IMAGE_LAYOUT_GENERAL);
  r.overdraw = g.image("overdraw", overdraw, VK_IMAGE_LAYOUT_GENERAL);
  return r;
}

// Setup: the counters reset, the history cleared after a cut, the overdraw counter cleared, and the scene's changed
// object records uploaded (one scatter dispatch).
void Renderer::Impl::declareSetup(Graph& g, const FrameResources& r, const FrameOptions& options,
                                  const FramePlan& plan, FrameSlot& slot) {
  std::vector<Graph::Use> uses;
  if (!plan.frozen) uses.push_back(Graph::writes(r.stats, access::transferWrite));
  // (a late-only frame: nothing was drawn early, so no object may count as drawn early; FramePlan::lateOnly)
  const bool clearHistory = historyDirty || plan.lateOnly;
  if (clearHistory) uses.push_back(Graph::overwrites(r.history, access::transferWrite));
  if (options.countOverdraw)
    uses.push_back(Graph::overwrites(r.overdraw, access::inLayout(access::transferWrite, VK_IMAGE_LAYOUT_GENERAL)));
  historyDirty = false;
  Graph::Pass& p = g.pass("setup").sideEffect();
  p.step(std::move(uses), [this, frozen = plan.frozen, clearHistory, overdrawCount = options.countOverdraw](VkCommandBuffer cmd) {
    if (!frozen) {  // frozen: keep the counts (and the micro-raster's arguments)
      vkCmdFillBuffer(cmd, stats.handle(), 0, STAT_COUNT * sizeof(uint32_t), 0);
      // Per phase: the micro-raster's dispatch (0 x 1 x 1) and merge draw (0, 1, 0, 0), then the cluster list's
      // count and dispatch (0 x 1 x 1), then the retest list's count and dispatch (0 x 1 x 1).
      const uint32_t args[STAT_BUFFER_UINTS - SW_ARGS] = {0, 1, 1, 0, 1, 0, 0, 0, 0, 1, 1, 0, 1, 0, 0, 0,
                                                          0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1};
      static_assert(STAT_BUFFER_UINTS - SW_ARGS == 2 * SW_ARGS_UINTS + 2 * CLUSTER_ARGS_UINTS + 4);
      vkCmdUpdateBuffer(cmd, stats.handle(), SW_ARGS * sizeof(uint32_t), sizeof(args), args);
    }
    if (overdrawCount) {
      VkClearColorValue zero{};
      VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
      vkCmdClearColorImage(cmd, overdraw.handle(), VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
    }
    if (clearHistory) {
      vkCmdFillBuffer(cmd, history.handle(), 0, VK_WHOLE_SIZE, 0);
      resetVisibleList(cmd);
    }
  });
  if (!dirty.empty())
    p.step({Graph::writes(r.scene, access::computeReadWrite)},
           [this, &slot, &st = slot.stats](VkCommandBuffer cmd) { recordObjectUploads(cmd, slot, st); });
}

void Renderer::Impl::declareSkin(Graph& g, const FrameResources& r) {
  g.pass("skin", "skin").step({Graph::writes(r.scene, access::computeReadWrite)}, [this](VkCommandBuffer cmd) {
    skin.record(cmd, animation->instanceCount(), animation->maxVertices());
  });
}

// A cull phase: early (all objects; occlusion: last frame's visible list) or late (occlusion: every object against
// the pyramid, then the ones the coarse test kept at a finer level).
void Renderer::Impl::declareCull(Graph& g, const FrameResources& r, const FramePlan& plan, uint32_t phase,
                                 const char* name) {
  const bool occlusion = plan.cull == CullMode::Occlusion, late = phase == CULL_PHASE_LATE;
  const gpu::Access lists = access::computeReadWrite | access::indirect;
  // (the stats buffer also holds the cluster dispatch's indirect arguments)
  auto cullUses = [&] {
    std::vector<Graph::Use> u = {Graph::reads(r.scene, access::computeRead),
                                 Graph::writes(r.stats, access::computeReadWrite | access::indirect),
                                 Graph::writes(r.draws, access::computeReadWrite), Graph::writes(r.history, lists)};
    if ((late && plan.usePyramid) || (!late && plan.earlyClusterOcclusion))  // (early: last frame's pyramid)
      u.push_back(Graph::reads(r.pyramid, access::inLayout(access::computeSampled, VK_IMAGE_LAYOUT_GENERAL)));
    return u;
  };
  Graph::Pass& p = g.pass(name, name);
  if (occlusion && late)  // it lists the visible set anew, after the early phase read it
    p.prepare({Graph::writes(r.history, access::transferWrite)}, [this](VkCommandBuffer cmd) { resetVisibleList(cmd); });
  if (occlusion && !late) {
    p.step(cullUses(), [this](VkCommandBuffer cmd) {
      cull.recordListed(cmd, sceneSet, visibleList, 0, CULL_PHASE_EARLY, 0);
    });
  } else if (occlusion) {  // the frustum sieve over every object, then the late cull over those inside
    p.step(cullUses(), [this](VkCommandBuffer cmd) { cull.recordSieve(cmd, sceneSet, gpuScene.objectCount); });
    p.step(cullUses(), [this](VkCommandBuffer cmd) {
      cull.recordListed(cmd, sceneSet, visibleList, lateListOffset(), CULL_PHASE_LATE, CULL_LATE_LISTED);
    });
  } else {
    p.step(cullUses(), [this, phase](VkCommandBuffer cmd) { cull.record(cmd, sceneSet, gpuScene.objectCount, phase); });
  }
  if (occlusion && late && plan.usePyramid)  // the objects the coarse pyramid test left, at a finer level
    p.step(cullUses(), [this](VkCommandBuffer cmd) {
      cull.recordListed(cmd, sceneSet, visibleList, refineListOffset(), CULL_PHASE_LATE, CULL_REFINE);
    });
  if (occlusion && late)  // how many of the listed objects those tests found occluded
    p.step(cullUses(), [this](VkCommandBuffer cmd) { cull.recordOcclusionCount(cmd, sceneSet); });
  if (occlusion && late)  // the objects those tests found visible and the early phase did not draw: LOD, routing
    p.step(cullUses(), [this](VkCommandBuffer cmd) {
      cull.recordListed(cmd, sceneSet, visibleList, lateDrawListOffset(), CULL_PHASE_LATE, CULL_LATE_DRAW);
    });
  if (plan.clusters)  // the clusters of the objects this phase listed for them
    p.step(cullUses(), [this, phase](VkCommandBuffer cmd) {
      cull.recordListed(cmd, sceneSet, stats, (CLUSTER_ARGS + phase * CLUSTER_ARGS_UINTS) * sizeof(uint32_t), phase,
                        CULL_CLUSTERS);
    });
  if (late && plan.earlyClusterOcclusion)  // the clusters the early phase deferred, against this frame's pyramid
    p.step(cullUses(), [this](VkCommandBuffer cmd) {
      cull.recordListed(cmd, sceneSet, stats, RETEST_ARGS * sizeof(uint32_t), CULL_PHASE_LATE, CULL_CLUSTER_RETEST);
    });
}

// The draw lists of a phase, in drawing order (draw buffer regions and counts: the cull pass's).
std::vector<passes::VisibilityList> Renderer::Impl::phaseLists(uint32_t phase) const {
  std::vector<passes::VisibilityList> lists;
  for (uint32_t l = 0; l < DRAW_LISTS; ++l)
    if (listCapacity[l] > 0)
      lists.push_back({l, phase * capacity + listFirst[l], STAT_LIST_DRAWS + phase * DRAW_LISTS + l, listCapacity[l]});
  return lists;
}

// A raster phase of the culled frame: the visibility pass into the IDs (or the G-buffer baseline into its targets)
// and depth, cleared by the first phase and kept by the late one.
void Renderer::Impl::declareRaster(Graph& g, const FrameResources& r, const FrameOptions& options,
                                   const FramePlan& plan, uint32_t phase, bool clear, const char* name) {
  const bool deferred = options.path == RenderPath::GBuffer;
  auto target = [&](Graph::Resource res, gpu::Access a) { return clear ? Graph::overwrites(res, a) : Graph::writes(res, a); };
  // On a GPU the single-sampled IDs are cleared by a compute store, and the raster loads them (its attachment clear
  // of them took 0.29 of 0.56 ms at 1080p on the H100).
  const bool computeClear = clear && !deferred && !plan.msaa && !facts().cpuDevice;
  Graph::Pass& pass = g.pass(name, name);
  if (computeClear)
    pass.step({Graph::overwrites(r.ids, access::inLayout(access::computeStorageImage, VK_IMAGE_LAYOUT_GENERAL))},
              [this](VkCommandBuffer cmd) {
                shade.recordClearIds(cmd, sceneSet, config.width, config.height, encoding.wide);
              });
  std::vector<Graph::Use> uses = {Graph::reads(r.draws, access::indirect | access::rasterRead),
                                  Graph::reads(r.stats, access::indirect), Graph::reads(r.scene, access::rasterRead),
                                  target(r.depth, access::depthAttachment)};
  if (deferred)
    for (Graph::Resource t : r.gbuffer) uses.push_back(target(t, access::colorAttachment));
  else
    uses.push_back(computeClear ? Graph::writes(r.ids, access::colorAttachment) : target(r.ids, access::colorAttachment));
  if (options.countOverdraw)
    uses.push_back(Graph::writes(r.overdraw, access::inLayout(access::rasterReadWrite, VK_IMAGE_LAYOUT_GENERAL)));
  pass.step(std::move(uses), [this, phase, clear, deferred, computeClear, msaa = plan.msaa,
                                            overdrawCount = options.countOverdraw](VkCommandBuffer cmd) {
    auto common = [&](auto& in) {
      in.depth = deferred ? &depth : msaa ? &depthMs : &depth;
      in.indexBuffer = gpuScene.indices.handle();
      in.draws = draws.handle();
      in.drawCount = stats.handle();
      in.lists = phaseLists(phase);
      in.clear = clear;
      in.countOverdraw = overdrawCount;
    };
    if (deferred) {
      passes::GBufferInputs in;
      for (uint32_t i = 0; i < GBUFFER_TARGETS; ++i) in.targets[i] = &gbufferTargets[i];
      common(in);
      gbuffer.record(cmd, sceneSet, in);
    } else {
      passes::VisibilityInputs in;
      in.ids = msaa ? &idsMs : &ids;
      common(in);
      in.idsCleared = computeClear;
      (msaa ? visibilityMs : visibility).record(cmd, sceneSet, in);
    }
  });
}

// The software micro-raster of a phase: the routed draws into the 64-bit buffer (cleared by the first phase),
// then (merge) merged into the IDs and depth the raster left as attachments. Without the merge the pyramid and the
// shading read the buffer themselves (FramePlan::swResolved).
void Renderer::Impl::declareMicroRaster(Graph& g, const FrameResources& r, uint32_t phase, bool clear, bool merge) {
  const bool late = !clear;  // (names: a late-only frame's one phase is the frame's first)
  Graph::Pass& raster = g.pass(late ? "micro-raster late" : "micro-raster", late ? "sw raster late" : "sw raster");
  if (clear)
    raster.prepare({Graph::overwrites(r.sw, access::transferWrite)},
                [this](VkCommandBuffer cmd) { vkCmdFillBuffer(cmd, swRaster.buffer.handle(), 0, VK_WHOLE_SIZE, 0); });
  raster.step({Graph::writes(r.sw, access::computeReadWrite), Graph::writes(r.stats, access::computeReadWrite | access::indirect),
               Graph::reads(r.draws, access::computeRead), Graph::reads(r.scene, access::computeRead)},
              [this, phase](VkCommandBuffer cmd) { swRaster.recordRaster(cmd, sceneSet, phase, stats); });
  if (!merge) return;
  const gpu::Access swRead{VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT};
  g.pass(late ? "micro-raster merge late" : "micro-raster merge", late ? "sw merge late" : "sw merge")
      .step({Graph::reads(r.sw, swRead), Graph::reads(r.stats, access::indirect),
             Graph::writes(r.ids, access::colorAttachment), Graph::writes(r.depth, access::depthAttachment)},
            [this, phase](VkCommandBuffer cmd) { swRaster.recordMerge(cmd, sceneSet, ids, depth, stats, phase); });
}

void Renderer::Impl::declarePyramid(Graph& g, const FrameResources& r, bool msaa, bool writeLevel0, bool microRaster) {
  std::vector<Graph::Use> uses = {Graph::reads(r.depth, access::computeSampled),
                                  Graph::overwrites(r.pyramid, access::inLayout(access::computeStorageImage |
                                                                                     access::computeSampled,
                                                                                 VK_IMAGE_LAYOUT_GENERAL))};
  if (microRaster) uses.push_back(Graph::reads(r.sw, access::computeRead));
  g.pass("depth pyramid", "depth pyramid").step(std::move(uses), [this, msaa, writeLevel0, microRaster](VkCommandBuffer cmd) {
    pyramid.record(cmd, msaa, writeLevel0, microRaster);
  });
}

// Tile light lists from the final depth.
void Renderer::Impl::declareLightCull(Graph& g, const FrameResources& r, bool msaa) {
  g.pass("light cull", "light cull")
      .step({Graph::reads(r.depth, access::computeSampled),
             Graph::overwrites(r.lightTiles, access::transferWrite | access::computeReadWrite)},
            [this, msaa](VkCommandBuffer cmd) { lightCull.record(cmd, sceneSet, msaa); });
}

void Renderer::Impl::declareClassify(Graph& g, const FrameResources& r) {
  const gpu::Access texels{VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT};
  g.pass("classify", "classify")
      .step({Graph::reads(r.ids, access::computeSampled), Graph::reads(r.draws, texels),
             Graph::reads(r.scene, access::computeRead),
             Graph::overwrites(r.classification, access::transferWrite | access::computeReadWrite | access::transferRead)},
            [this](VkCommandBuffer cmd) { classify.recordClassify(cmd, sceneSet); });
}

// The shading pass: the colour cleared to the background, then every covered pixel (or tile, or classified tile)
// shaded from the IDs.
void Renderer::Impl::declareShade(Graph& g, const FrameResources& r, const FrameOptions& options, const FramePlan& plan) {
  Graph::Pass& p = g.pass("shade", "shade");
  p.step({Graph::overwrites(r.color, access::transferWrite)}, [this](VkCommandBuffer cmd) {
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, color.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &kBackground, 1, &range);
  });
  // The shading's own counters (a frozen frame keeps the cull counts, not these): per-sample pixels (MSAA) and
  // covered pixels; and the attribute record, zero where nothing is drawn.
  std::vector<Graph::Use> fills = {Graph::writes(r.stats, access::transferWrite)};
  if (options.readAttributes) fills.push_back(Graph::overwrites(r.attributes, access::transferWrite));
  p.step(std::move(fills), [this, msaa = plan.msaa, attributesToo = options.readAttributes](VkCommandBuffer cmd) {
    if (attributesToo) vkCmdFillBuffer(cmd, attributes.handle(), 0, VK_WHOLE_SIZE, 0);
    if (msaa) vkCmdFillBuffer(cmd, stats.handle(), STAT_PER_SAMPLE_PIXELS * sizeof(uint32_t), sizeof(uint32_t), 0);
    vkCmdFillBuffer(cmd, stats.handle(), STAT_COVERED_PIXELS * sizeof(uint32_t), sizeof(uint32_t), 0);
  });
  const gpu::Access texels{VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT};
  std::vector<Graph::Use> uses = {Graph::reads(r.ids, access::computeSampled), Graph::reads(r.draws, texels),
                                  Graph::reads(r.scene, access::computeRead),
                                  Graph::writes(r.color, access::computeStorageImage),
                                  Graph::writes(r.stats, access::computeReadWrite)};
  if (options.readAttributes) uses.push_back(Graph::writes(r.attributes, access::computeReadWrite));
  if (plan.lightsCulled) uses.push_back(Graph::reads(r.lightTiles, access::computeRead));
  if (plan.swResolved) {  // the micro-raster's fragments, and the depth they are compared with
    uses.push_back(Graph::reads(r.sw, access::computeRead));
    uses.push_back(Graph::reads(r.depth, access::computeSampled));
  }
  if (plan.shading == ShadingMode::Classified)
    uses.push_back(Graph::reads(r.classification, access::computeRead | access::indirect));
  if (plan.coveredPixels)
    uses.push_back(Graph::overwrites(r.coveredPixels, access::transferWrite | access::computeReadWrite | access::indirect));
  p.step(std::move(uses), [this, plan, attributesToo = options.readAttributes](VkCommandBuffer cmd) {
    const uint32_t w = config.width, h = config.height;
    if (plan.shading == ShadingMode::Classified)
      classify.recordShade(cmd, sceneSet);
    else if (plan.coveredPixels)
      shade.recordCovered(cmd, sceneSet, coveredPixels, w, h, plan.swResolved);
    else
      shade.record(cmd, sceneSet, w, h,
                   plan.msaa      ? passes::ShadePass::Msaa
                   : attributesToo ? passes::ShadePass::Attributes
                                   : passes::ShadePass::Plain,
                   plan.swResolved);
  });
}

// MSAA with readIds: every sample's (object + 1, triangle) into the attribute buffer (untimed).
void Renderer::Impl::declareSampleIds(Graph& g, const FrameResources& r) {
  g.pass("sample ids")
      .step({Graph::reads(r.ids, access::computeSampled), Graph::reads(r.draws, access::computeRead),
             Graph::overwrites(r.attributes, access::computeReadWrite)},
            [this](VkCommandBuffer cmd) { shade.recordSampleIds(cmd, sceneSet, config.width, config.height); });
}

// G-buffer baseline: the targets and the depth sampled by the lighting pass, which writes the covered pixels of
// the (background-cleared) colour image.
void Renderer::Impl::declareGBufferLighting(Graph& g, const FrameResources& r, bool writeAttributes) {
  Graph::Pass& p = g.pass("lighting", "lighting");
  p.step({Graph::overwrites(r.color, access::transferWrite)}, [this](VkCommandBuffer cmd) {
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, color.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &kBackground, 1, &range);
  });
  if (writeAttributes)
    p.step({Graph::overwrites(r.attributes, access::transferWrite)},
           [this](VkCommandBuffer cmd) { vkCmdFillBuffer(cmd, attributes.handle(), 0, VK_WHOLE_SIZE, 0); });
  std::vector<Graph::Use> uses = {Graph::reads(r.depth, access::computeSampled), Graph::reads(r.scene, access::computeRead),
                                  Graph::writes(r.color, access::computeStorageImage)};
  for (Graph::Resource t : r.gbuffer) uses.push_back(Graph::reads(t, access::computeSampled));
  if (writeAttributes) uses.push_back(Graph::writes(r.attributes, access::computeReadWrite));
  p.step(std::move(uses), [this, writeAttributes](VkCommandBuffer cmd) {
    gbufferLighting.record(cmd, sceneSet, config.width, config.height, writeAttributes);
  });
}

// The forward baseline: CPU culling (one draw per object), then one raster pass into colour and depth (MSAA:
// multisampled colour and depth, the colour resolved into `color` by the hardware).
void Renderer::Impl::declareForward(Graph& g, const FrameResources& r, const Camera& camera, const FrameMath& math,
                                    const FrameOptions& options, FrameStats& st, FrameResult* result) {
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
  std::vector<Graph::Use> uses = {Graph::reads(r.scene, access::rasterRead),
                                  Graph::overwrites(r.color, access::colorAttachment),
                                  Graph::overwrites(r.depth, access::depthAttachment)};
  if (msaa) uses.push_back(Graph::overwrites(r.colorMs, access::colorAttachment));
  if (options.readIds) uses.push_back(Graph::overwrites(r.forwardIds, access::colorAttachment));
  if (options.countOverdraw)
    uses.push_back(Graph::writes(r.overdraw, access::inLayout(access::rasterReadWrite, VK_IMAGE_LAYOUT_GENERAL)));
  g.pass("forward", "forward")
      .step(std::move(uses), [this, msaa, fdraws = std::move(fdraws), readIds = options.readIds,
                              overdrawCount = options.countOverdraw](VkCommandBuffer cmd) {
        (msaa ? forwardMs : forward)
            .record(cmd, sceneSet, msaa ? colorMs : color, kBackground, msaa ? depthMs : depth,
                    gpuScene.indices.handle(), fdraws, readIds ? &forwardIds : nullptr, overdrawCount,
                    msaa ? &color : nullptr);
      });
  st.targetBytesPerPixel = (4 /*depth*/ + 8 /*colour*/) * options.msaa + (msaa ? 8 /*resolved colour*/ : 0);
  st.rasterBytesPerFragment = 4 /*depth*/ + 8 /*colour*/;
}

// BLEND objects over the opaque frame: sorted back to front, depth tested against the opaque depth, not written.
void Renderer::Impl::declareTransparent(Graph& g, const FrameResources& r, const Camera& camera, const FrameMath& math,
                                        const FrameOptions& options, FrameStats& st) {
  const gpu::Access depthTest{access::kDepthStages, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT,
                                 VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL};
  g.pass("transparent", "transparent")
      .step({Graph::reads(r.scene, access::rasterRead), Graph::writes(r.color, access::colorAttachment),
             Graph::reads(r.depth, depthTest)},
            [this, draws = transparentCull(camera, math, options, st)](VkCommandBuffer cmd) {
              transparent.record(cmd, sceneSet, color, depth, gpuScene.indices.handle(), draws);
            });
}

// The counters into the slot's readback buffer (read when the frame has finished).
void Renderer::Impl::declareCounters(Graph& g, const FrameResources& r, FrameSlot& slot) {
  g.pass("counters").sideEffect().step({Graph::reads(r.stats, access::transferRead)}, [this, &slot](VkCommandBuffer cmd) {
    VkBufferCopy statsCopy{0, 0, STAT_COUNT * sizeof(uint32_t)};
    vkCmdCopyBuffer(cmd, stats.handle(), slot.statsReadback.handle(), 1, &statsCopy);
  });
}

}  // namespace visbuf
