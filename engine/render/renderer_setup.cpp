// Renderer creation and the resources it owns: descriptor sets, screen targets, lazily created MSAA,
// G-buffer and classification resources.
#include "visbuf/render/renderer_impl.h"

#include <algorithm>
#include <bit>
#include <cstring>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace visbuf {

void Renderer::Impl::createLayouts() {
  VkDevice dev = device.device();
  sceneSets.create(device, uint32_t(slots.size()));
  for (FrameSlot& f : slots) {
    VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cai.commandPool = device.commandPool();
    cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cai.commandBufferCount = kCommandBuffers;
    VK_CHECK(vkAllocateCommandBuffers(dev, &cai, f.cmds.data()));
    f.frameBuffer =
        gpu::Buffer(device, sizeof(gpu::FrameData), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, gpu::MemoryUse::HostVisible);
    f.statsReadback = gpu::Buffer(device, STAT_COUNT * sizeof(uint32_t), VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                  gpu::MemoryUse::HostVisible);
    f.timestamps = std::make_unique<gpu::TimestampPool>(device, 16);
  }
  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = sci.minFilter = VK_FILTER_NEAREST;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  sci.maxLod = VK_LOD_CLAMP_NONE;
  VK_CHECK(vkCreateSampler(dev, &sci, nullptr, &sampler));
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VK_CHECK(vkCreateFence(dev, &fci, nullptr, &fence));
}

void Renderer::Impl::createTargets(uint32_t width, uint32_t height) {
  vkDeviceWaitIdle(device.device());
  const VkFormat idFormat = encoding.wide ? VK_FORMAT_R32G32_UINT : VK_FORMAT_R32_UINT;
  ids = gpu::Image(device, idFormat, width, height,
                   VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                       VK_IMAGE_USAGE_STORAGE_BIT,
                   VK_IMAGE_ASPECT_COLOR_BIT);
  depth = gpu::Image(device, VK_FORMAT_D32_SFLOAT, width, height,
                     VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_DEPTH_BIT);
  pyramid.resize(depth);
  color = gpu::Image(device, VK_FORMAT_R16G16B16A16_SFLOAT, width, height,
                     VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT |
                         VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                     VK_IMAGE_ASPECT_COLOR_BIT);
  coveredPixels = gpu::Buffer(device, coveredListWords(width, height) * sizeof(uint32_t),
                             VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                 VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                 VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT,
                             gpu::MemoryUse::DeviceLocal);
  // (as much of it as one texel view holds: SceneFacts::coveredListFits says whether that is all of it)
  coveredTexels = gpu::BufferView(device, coveredPixels, VK_FORMAT_R32_UINT, 0,
                                  std::min<VkDeviceSize>(coveredListWords(width, height),
                                                         device.properties().limits.maxTexelBufferElements) *
                                      sizeof(uint32_t));
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

// The attribute buffer is only as large as asked for (a full-screen one is 64 bytes per pixel).
void Renderer::Impl::resizeAttributes(VkDeviceSize bytes) {
  attributes = gpu::Buffer(device, bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                              VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                           gpu::MemoryUse::DeviceLocal);
  attributesReadback.reset();
}

void Renderer::Impl::writeDescriptors() {
  vkDeviceWaitIdle(device.device());
  for (uint32_t i = 0; i < slots.size(); ++i)
    sceneSets.write(i, slots[i].frameBuffer, {&gpuScene, &stats, objectSplit, vertexShift});
  bindPasses();
}

void Renderer::Impl::bindPasses() {
  cull.bind(draws, history, visibleList, drawLists, pyramid.pyramid(), sampler, gpuScene.clusters);
  visibility.bind(overdraw);
  if (visibilityMs.layout) visibilityMs.bind(overdraw);
  if (swRaster.created()) swRaster.bind(draws, drawLists);
  pyramid.bindMicroRaster(swRaster.texels.handle());
  // MSAA frames: the light culling reads the multisampled depth.
  if (hasPointLights()) lightCull.bind(pointLights, descriptorsMsaa ? depthMs : depth, sampler);
  forward.bind(boundLights(), boundLightTiles(), overdraw);
  if (forwardMs.layout) forwardMs.bind(boundLights(), boundLightTiles(), overdraw);
  if (transparent.created()) transparent.bind(boundLights(), boundLightTiles());
  if (gbuffer.created()) gbuffer.bind(overdraw);
  // MSAA frames: the shading reads the multisampled IDs.
  const passes::ShadeInputs shading{&boundLights(), &boundLightTiles(), &draws, drawTexels.handle(),
                                    descriptorsMsaa ? &idsMs : &ids, sampler, &color, &attributes, &ids, &depth,
                                    swRaster.texels.handle(), coveredTexels.handle()};
  shade.bind(shading);
  if (classify.created()) classify.bind(shading);
  // G-buffer targets: until a G-buffer frame creates them (again, after a resize), the depth stands in.
  passes::GBufferLightingInputs lighting{&boundLights(), &boundLightTiles(), {}, &depth, sampler, &color, &attributes};
  for (uint32_t i = 0; i < GBUFFER_TARGETS; ++i) lighting.targets[i] = gbufferTargets[i] ? &gbufferTargets[i] : &depth;
  if (gbufferLighting.created()) gbufferLighting.bind(lighting);
}

// The G-buffer pipelines and targets at the current size (only renderers that draw the G-buffer baseline pay
// for them).
void Renderer::Impl::ensureGBufferTargets() {
  if (!gbuffer.created()) {
    gbuffer = passes::GBufferPass::create(device, sceneSets.layout(), textured, listMask);
    gbufferLighting = passes::GBufferLightingPass::create(device, sceneSets.layout(), textured.windowed,
                                                          textured.materialFeatures);
  }
  if (gbufferTargets[0]) return;
  for (uint32_t i = 0; i < GBUFFER_TARGETS; ++i)
    gbufferTargets[i] = gpu::Image(device, gbuffer.formats.color[i], config.width, config.height,
                                   VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                                   VK_IMAGE_ASPECT_COLOR_BIT);
  writeDescriptors();
}

// FrameOptions::msaa against the device and the frame's other options (what MSAA does not cover is refused).
Status Renderer::Impl::checkMsaa(const FrameOptions& o) const {
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
void Renderer::Impl::prepareMsaa(const FrameOptions& options) {
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
    if (visibilityMsSamples != options.msaa) {
      visibilityMs = passes::VisibilityPass::create(device, sceneSets.layout(), textured, listMask, samples);
      visibilityMs.bind(overdraw);
    }
    visibilityMsSamples = options.msaa;
    shade.createMsaa(device, textured);
  }
  if (msaa && options.path == RenderPath::Forward) {
    if (forwardMsSamples != options.msaa) {
      forwardMs = passes::ForwardPass::create(device, sceneSets.layout(), textured, listMask, samples);
      forwardMs.bind(boundLights(), boundLightTiles(), overdraw);
    }
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
void Renderer::Impl::ensureClassify() {
  if (classify.created()) return;
  std::vector<passes::ClassifyPass::Variant> variants;  // per material: samples a texture, its shading features
  for (const Material& m : scene.materials)
    variants.push_back({packMaterial(m, scene).slotCount > 0, materialFeatures(m)});
  classify.create(device, sceneSets.layout(), textured, std::move(variants));
  classify.resize(device, config.width, config.height);
  writeDescriptors();
}

Renderer::Renderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Renderer::~Renderer() = default;

Result<std::unique_ptr<Renderer>> Renderer::create(gpu::Device& device, const Scene& scene,
                                                   const RendererConfig& config) {
  return gpu::catchVulkan([&]() -> Result<std::unique_ptr<Renderer>> {
    if (config.width == 0 || config.height == 0 || config.width > 16384 || config.height > 16384)
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("image size {}x{} outside 1..16384", config.width, config.height));
    if (config.framesInFlight < 1 || config.framesInFlight > 4)
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("framesInFlight {} outside 1..4", config.framesInFlight));
    if (uint64_t(scene.objects.size()) + config.spareObjects > (1ull << 31))
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("{} objects + {} spare slots: more than 2^31 object IDs", scene.objects.size(),
                                   config.spareObjects));
    auto impl = std::make_unique<Impl>(device, scene);
    impl->config = config;
    impl->slots.resize(config.framesInFlight);
    Result<GpuScene> g = uploadScene(device, scene, config.spareObjects);
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
    const uint32_t sceneObjects = uint32_t(scene.objects.size());
    for (uint32_t i = 0; i < sceneObjects; ++i) {
      const uint32_t l = impl->gpuScene.objectList[i];
      if (l == DRAW_LIST_NONE)
        impl->blendObjects.push_back(i);
      else
        ++listObjects[l], ++listed, ++impl->listLive[l];
    }
    // Spare slots: every list has room for all of them (an added object may land in any list).
    if (config.spareObjects)
      for (uint32_t l = 0; l < DRAW_LISTS; ++l) listObjects[l] += config.spareObjects, listed += config.spareObjects;
    impl->objects = scene.objects;
    impl->objects.resize(sceneObjects + config.spareObjects);
    impl->slotState.assign(sceneObjects + config.spareObjects, Impl::SlotFree);
    std::fill_n(impl->slotState.begin(), sceneObjects, Impl::SlotLive);
    for (uint32_t i = sceneObjects + config.spareObjects; i-- > sceneObjects;) impl->freeSlots.push_back(i);
    impl->dirtyIndex.assign(impl->slotState.size(), 0);
    impl->skinnedObject.assign(impl->slotState.size(), 0);
    impl->rigidObject.assign(impl->slotState.size(), 0);
    for (const RigidObject& ro : impl->scene.rigidObjects) impl->rigidObject[ro.object] = 1;
    for (const SkinnedObject& so : scene.skinnedObjects) impl->skinnedObject[so.object] = 1;
    const uint64_t rangeSlots = maxRange / (2 * sizeof(gpu::DrawCommand));
    // Cluster draws (config.h CULL_CLUSTERS) get a reserve beyond one draw per object, shared out among the lists by
    // their objects: as many as fit without costing the ID encoding anything -- the narrow 32-bit IDs where the objects'
    // slots allow them, else the micro-raster's full triangle cap (2^21 slots), else the power of two the objects'
    // slots need --, at least 4,096, at most 2^18 and at most every object's largest level in clusters. Only lists
    // whose region holds every object get one; an object whose clusters do not fit is drawn whole.
    constexpr uint64_t kMinClusterReserve = 4096, kMaxClusterReserve = uint64_t{1} << 18;
    const uint32_t triangleBits = chooseIdEncoding(1, impl->gpuScene.maxTrianglesPerDraw, false).triangleBits;
    const uint64_t objectSlots = 2 * listed;
    const uint64_t narrowSlots = (uint64_t{1} << (32 - std::min(triangleBits, 31u))) - 1;
    const uint64_t swSlots = uint64_t{1} << (32 - std::bit_width(SW_RASTER_MAX_TRIANGLES - 1));
    const uint64_t slotLimit = objectSlots <= narrowSlots ? narrowSlots
                               : objectSlots <= swSlots   ? swSlots
                                                          : std::bit_ceil(objectSlots);
    const uint64_t reserveTotal =
        config.drawCapacity || listed > rangeSlots || impl->gpuScene.clusterCount == 0
            ? 0
            : std::min<uint64_t>({std::max(slotLimit / 2 - listed, kMinClusterReserve), kMaxClusterReserve,
                                  listed * impl->gpuScene.maxClustersPerLod, rangeSlots - listed});
    for (uint32_t l = 0; l < DRAW_LISTS; ++l) {
      uint64_t c = listObjects[l];
      if (config.drawCapacity)
        c = std::min<uint64_t>(c, config.drawCapacity);
      else if (listed > rangeSlots)
        c = std::max<uint64_t>(c ? 1 : 0, c * rangeSlots / listed);
      const uint64_t reserve = c == listObjects[l] && listed ? reserveTotal * c / listed : 0;
      impl->listFirst[l] = impl->capacity;
      impl->listCapacity[l] = uint32_t(c + reserve);
      impl->listClusterReserve[l] = uint32_t(reserve);
      impl->capacity += uint32_t(c + reserve);
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
    gpu::Specialization textured(w, uint32_t(impl->gpuScene.textureClasses.size()),
                                 impl->gpuScene.skinned.empty() ? 0u : 1u, texels ? 1u : 0u);
    const auto& meshTable = impl->gpuScene.meshTable;
    textured.extras = std::any_of(meshTable.begin(), meshTable.end(),
                                  [](const gpu::MeshData& m) { return m.extraOffset != EXTRA_NONE; }) ? 1u : 0u;
    textured.pointLights = impl->hasPointLights() ? 1u : 0u;
    textured.materialFeatures = 0u;
    for (const Material& m : scene.materials) textured.materialFeatures |= materialFeatures(m);
    impl->cull = passes::CullPass::create(device, impl->sceneSets.layout(), textured);
    impl->objectUpload.create(device);
    impl->visibility = passes::VisibilityPass::create(device, impl->sceneSets.layout(), textured, impl->listMask);
    impl->shade = passes::ShadePass::create(device, impl->sceneSets.layout(), textured);
    if (impl->swListMask) impl->swRaster = passes::SwRasterPass::create(device, impl->sceneSets.layout(), textured);
    impl->forward = passes::ForwardPass::create(device, impl->sceneSets.layout(), textured, impl->listMask);
    if (!impl->blendObjects.empty())
      impl->transparent = passes::TransparentPass::create(device, impl->sceneSets.layout(), textured);
    std::array<glm::uvec4, 2 * DRAW_LISTS> lists{};
    for (uint32_t l = 0; l < DRAW_LISTS; ++l) {
      lists[l] = {impl->listFirst[l], impl->capacity + impl->listFirst[l], impl->listCapacity[l],
                  impl->swListMask >> l & 1u};
      lists[DRAW_LISTS + l] = {impl->listClusterReserve[l], 0, 0, 0};
    }
    impl->drawLists = gpu::Buffer(device, sizeof(lists), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, gpu::MemoryUse::HostVisible);
    std::memcpy(impl->drawLists.mapped(), lists.data(), sizeof(lists));
    impl->textured = textured;  // the G-buffer pipelines are created by the first G-buffer frame
    impl->draws = gpu::Buffer(device, drawBytes,
                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                  VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT,
                              gpu::MemoryUse::DeviceLocal);
    impl->drawTexels = gpu::BufferView(device, impl->draws, VK_FORMAT_R32_UINT, 0,
                                       std::min<VkDeviceSize>(drawBytes / 4, maxTexels) * 4);
    impl->stats = gpu::Buffer(device, STAT_BUFFER_UINTS * sizeof(uint32_t),
                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                  VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                              gpu::MemoryUse::DeviceLocal);
    impl->history = gpu::Buffer(device, std::max<uint64_t>(16, uint64_t(impl->gpuScene.objectCount) * 4),
                                VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                gpu::MemoryUse::DeviceLocal);
    // The visible list, the refinement list, the cluster lists' (object, LOD) entries (config.h CLUSTER_ARGS), the
    // late list (LATE_LIST_WORD), the retest list's entries (RETEST_LIST_WORD), then the late draw list
    // (LATE_DRAW_LIST_WORD).
    impl->visibleList = gpu::Buffer(device, (impl->lateDrawListOffset() / 4 + VISIBLE_LIST_HEADER +
                                             uint64_t(impl->gpuScene.objectCount)) * 4,
                                    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                                        VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT,
                                    gpu::MemoryUse::DeviceLocal);
    impl->pyramid.create(device);
    if (impl->hasPointLights()) {  // scenes without point lights allocate no light buffers at all
      std::vector<gpu::PointLightData> lights;
      for (const PointLight& l : scene.pointLights) {
        const glm::vec2 cone(spotAngleScaleOffset(l));
        lights.push_back({glm::vec4(glm::vec3(l.position - scene.anchor), l.range), glm::vec4(l.color, l.intensity),
                          glm::vec4(l.direction, 0.0f), cone.x, cone.y, uint32_t(l.type), 0u});
      }
      impl->pointLights = gpu::uploadVector(device, lights, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
      impl->lightCull.create(device, impl->sceneSets.layout(), w);
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
  });
}

Status Renderer::resize(uint32_t width, uint32_t height) {
  return impl_->guarded([&]() -> Status {
    if (width == 0 || height == 0 || width > 16384 || height > 16384)
      return makeError(ErrorCode::InvalidArgument, fmt::format("image size {}x{} outside 1..16384", width, height));
    impl_->createTargets(width, height);
    impl_->frameHistory.cut();  // a new size: probe the pyramid again
    return {};  // the draw lists stay valid (they do not depend on the size): freezeCulling still works
  });
}

}  // namespace visbuf
