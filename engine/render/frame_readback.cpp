// What a headless frame reads back (renderFrame) and how the counters of a finished frame become its stats:
// the colour, the ID target decoded to (object + 1, triangle), draws, pyramid, overdraw and attributes.
#include "visbuf/render/renderer_impl.h"

#include <algorithm>

#include <glm/gtc/packing.hpp>

namespace visbuf {

// The copies into host-visible buffers, after every pass of the frame (renderFrame only).
void Renderer::Impl::declareReadback(Graph& g, const FrameResources& r, const FrameOptions& options,
                                     const FramePlan& plan, FrameReadback& rb) {
  const uint32_t w = config.width, h = config.height;
  const bool gpuCulled = plan.gpuCulled, msaa = plan.msaa, visbuf = options.path == RenderPath::Visbuf;
  const bool readIds = options.readIds;
  std::vector<Graph::Use> uses;
  if (plan.lightsCulled) uses.push_back(Graph::reads(r.lightTiles, access::transferRead));
  if (options.readColor) uses.push_back(Graph::reads(r.color, access::transferRead));
  rb.draws = (readIds || options.readDraws) && gpuCulled;
  if (rb.draws) {
    uses.push_back(Graph::reads(r.draws, access::transferRead));
    if (!drawsReadback)
      drawsReadback = gpu::Buffer(device, draws.size(), VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
  }
  rb.pyramid = plan.usePyramid && options.readPyramid;
  VkDeviceSize pyramidBytes = 0;
  std::vector<VkBufferImageCopy> pyramidRegions;
  if (rb.pyramid) {
    uses.push_back(Graph::reads(r.pyramid, access::transferRead));
    uint32_t lw = w, lh = h;
    for (uint32_t k = 0; k < pyramid.levels(); ++k) {
      VkBufferImageCopy region{};
      region.bufferOffset = pyramidBytes;
      region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, k, 0, 1};
      region.imageExtent = {lw, lh, 1};
      pyramidRegions.push_back(region);
      rb.pyramidSizes.emplace_back(lw, lh);
      pyramidBytes += VkDeviceSize(lw) * lh * 4;
      lw = (lw + 1) / 2;
      lh = (lh + 1) / 2;
    }
    if (!pyramidReadback || pyramidReadback.size() < pyramidBytes)
      pyramidReadback = gpu::Buffer(device, pyramidBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
  }
  if (options.countOverdraw) {
    uses.push_back(Graph::reads(r.overdraw, access::transferRead));
    if (!overdrawReadback)
      overdrawReadback = gpu::Buffer(device, VkDeviceSize(w) * h * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                     gpu::MemoryUse::HostVisible);
  }
  // MSAA IDs: the sample-ID pass wrote them into the attribute buffer.
  const bool sampleIds = readIds && visbuf && msaa;
  if (rb.attributes || sampleIds) uses.push_back(Graph::reads(r.attributes, access::transferRead));
  if (rb.attributes && !attributesReadback)
    attributesReadback = gpu::Buffer(device, attributes.size(), VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                     gpu::MemoryUse::HostVisible);
  if (readIds && !sampleIds) uses.push_back(Graph::reads(visbuf ? r.ids : r.forwardIds, access::transferRead));
  g.pass("readback").sideEffect().step(std::move(uses), [=, this, &rb](VkCommandBuffer cmd) {
    if (plan.lightsCulled) lightCull.recordReadback(cmd);
    if (options.readColor) copyImageToBuffer(cmd, color, colorReadback);
    if (rb.draws) {
      VkBufferCopy dc{0, 0, draws.size()};
      vkCmdCopyBuffer(cmd, draws.handle(), drawsReadback.handle(), 1, &dc);
    }
    if (rb.pyramid)
      vkCmdCopyImageToBuffer(cmd, pyramid.pyramid().handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                             pyramidReadback.handle(), uint32_t(pyramidRegions.size()), pyramidRegions.data());
    if (options.countOverdraw) copyImageToBuffer(cmd, overdraw, overdrawReadback);
    if (rb.attributes) {
      VkBufferCopy ac{0, 0, rb.attributeBytes};
      vkCmdCopyBuffer(cmd, attributes.handle(), attributesReadback.handle(), 1, &ac);
    }
    if (sampleIds) {
      VkBufferCopy c{0, 0, rb.sampleIdBytes};
      vkCmdCopyBuffer(cmd, attributes.handle(), idsReadback.handle(), 1, &c);
    } else if (readIds) {
      copyImageToBuffer(cmd, visbuf ? ids : forwardIds, idsReadback);
    }
  });
}

// What a frame's pyramid cost and what its raster paid per object drawn (the LOD histogram counts each drawn object
// once, whole or as clusters), from its GPU times (FrameHistory::finished).
static PyramidCost pyramidCost(const FrameStats& st) {
  double pyramidMs = 0.0, rasterMs = 0.0;
  for (const auto& [name, ms] : st.graph.passMs) {
    if (name == "depth pyramid") pyramidMs += ms;
    if (name == "raster early" || name == "raster late" || name == "sw raster" || name == "sw raster late")
      rasterMs += ms;
  }
  uint64_t objects = 0;
  for (uint32_t n : st.cull.lodHistogram) objects += n;
  return {pyramidMs, objects > 0 ? rasterMs / double(objects) : 0.0};
}

// The counters and GPU times of a finished frame (slot.stats already holds what recording knew), and the
// decisions later frames take from them (skipping a pyramid or micro-raster that did nothing). synchronous:
// renderFrame, which also reads the light and classification statistics (their buffers are single).
void Renderer::Impl::collectStats(FrameSlot& slot, bool synchronous) {
  slot.pending = false;
  FrameStats& st = slot.stats;
  const FrameOptions& options = slot.options;
  const bool gpuCulled = slot.plan.gpuCulled, msaa = slot.plan.msaa;
  const bool swOn = slot.plan.swOn;
  st.graph.passMs = slot.timestamps->read();
  if (st.lights.culled && synchronous) {
    const passes::LightCullStats ls = lightCull.stats();
    st.lights.tileOverflow = ls.overflowTiles;
    st.lights.dropped = ls.droppedLights;
    st.lights.maxPerTile = ls.maxPerTile;
    st.lights.meanPerTile = double(ls.pairs) / (double(lightCull.tilesX()) * lightCull.tilesY());
  }
  for (auto& p : st.graph.passMs) st.gpuMs += p.second;
  if (st.shade.mode == ShadingMode::Classified && synchronous) {
    passes::ClassifyStats cs = classify.stats();
    st.shade.materialsPresent = cs.materialsPresent;
    st.shade.classifiedTiles = cs.pairs;
    st.shade.materialTiles = std::move(cs.tiles);
    st.shade.materialPixels = std::move(cs.pixels);
  }
  if (gpuCulled) {
    const uint32_t* s = static_cast<const uint32_t*>(slot.statsReadback.mapped());
    st.shade.perSamplePixels = msaa ? s[STAT_PER_SAMPLE_PIXELS] : 0;
    const bool pixelsCounted = slot.options.path == RenderPath::Visbuf && !msaa;
    st.coveredPixels = pixelsCounted ? s[STAT_COVERED_PIXELS] : 0;
    if (pixelsCounted) frameHistory.shaded(st.coveredPixels, uint64_t(config.width) * config.height);  // (Auto shading)
    st.cull.objectsTested = gpuScene.objectCount;
    st.cull.frustumCulled = s[STAT_FRUSTUM_CULLED];
    st.cull.occlusionCulled = s[STAT_OCCLUSION_CULLED];
    st.cull.subpixelCulled = s[STAT_SUBPIXEL_CULLED];
    st.cull.refineTested = s[STAT_REFINE_TESTED];
    st.cull.refineOccluded = s[STAT_REFINE_OCCLUDED];
    st.cull.drawsEarly = st.cull.drawsLate = 0;
    for (uint32_t l = 0; l < DRAW_LISTS; ++l) {
      st.cull.drawsEarly += listDrawn(s, CULL_PHASE_EARLY, l) + listSwDrawn(s, CULL_PHASE_EARLY, l);
      st.cull.drawsLate += listDrawn(s, CULL_PHASE_LATE, l) + listSwDrawn(s, CULL_PHASE_LATE, l);
      st.sw.draws += listSwDrawn(s, CULL_PHASE_EARLY, l) + listSwDrawn(s, CULL_PHASE_LATE, l);
    }
    st.sw.on = swOn;
    st.sw.resolved = swOn && slot.plan.swResolved;
    st.sw.triangles = s[STAT_SW_TRIANGLES];
    st.sw.oversize = s[STAT_SW_OVERSIZE];
    st.cull.drawsAppended = s[STAT_DRAW_COUNT] + s[STAT_DRAW_COUNT_LATE];
    st.cull.drawsRendered = st.cull.drawsEarly + st.cull.drawsLate;
    st.cull.drawOverflow = s[STAT_DRAW_OVERFLOW];
    st.trianglesDrawn = s[STAT_TRIANGLES_DRAWN];
    st.cull.lodHistogram.assign(s + STAT_LOD_HISTOGRAM, s + STAT_LOD_HISTOGRAM + MAX_LODS);
    st.cull.clusters = {s[STAT_CLUSTER_OBJECTS],  s[STAT_CLUSTERS_TESTED],   s[STAT_CLUSTERS_FRUSTUM],
                        s[STAT_CLUSTERS_BACKFACING], s[STAT_CLUSTERS_OCCLUDED], s[STAT_CLUSTER_DRAWS],
                        s[STAT_CLUSTERS_DEFERRED], s[STAT_CLUSTERS_RECOVERED]};
    frameHistory.finished(slot.plan, options, device.isCpu(), st.sw.triangles, st.cull.drawsEarly, st.cull.occlusionCulled,
                          pyramidCost(st));
  }
  while (!st.cull.lodHistogram.empty() && st.cull.lodHistogram.back() == 0) st.cull.lodHistogram.pop_back();

}

void Renderer::Impl::decodeReadback(const FrameOptions& options, const FramePlan& plan, const FrameReadback& rb,
                                    const FrameSlot& frame, FrameResult& result) {
  const uint32_t w = config.width, h = config.height;
  const bool gpuCulled = plan.gpuCulled, msaa = plan.msaa;
  const bool readIds = options.readIds;
  FrameStats& st = result.stats;
  result.width = w;
  result.height = h;
  const size_t pixels = size_t(w) * h;
  if (options.readColor) {
    result.color.resize(pixels * 4);
    const uint16_t* half = static_cast<const uint16_t*>(colorReadback.mapped());
    for (size_t i = 0; i < pixels * 4; ++i) result.color[i] = glm::unpackHalf1x16(half[i]);
  }
  if (rb.draws) {
    const auto* dr = static_cast<const gpu::DrawCommand*>(drawsReadback.mapped());
    std::vector<char> seen(gpuScene.objectCount, 0);  // an object drawn as clusters has several draws
    auto add = [&](const gpu::DrawCommand& d) {
      if (d.firstInstance >= seen.size() || seen[d.firstInstance]) return;
      seen[d.firstInstance] = 1;
      result.drawnObjects.push_back(d.firstInstance);
      result.drawnLods.push_back(drawLod(d));
    };
    const uint32_t* s = static_cast<const uint32_t*>(frame.statsReadback.mapped());
    for (uint32_t phase : {CULL_PHASE_EARLY, CULL_PHASE_LATE})
      for (uint32_t l = 0; l < DRAW_LISTS; ++l) {
        for (uint32_t i = 0; i < listDrawn(s, phase, l); ++i) add(dr[phase * capacity + listFirst[l] + i]);
        for (uint32_t i = 0; i < listSwDrawn(s, phase, l); ++i)
          add(dr[phase * capacity + listFirst[l] + listCapacity[l] - 1 - i]);
      }
  }
  if (rb.pyramid) {
    const float* p = static_cast<const float*>(pyramidReadback.mapped());
    for (auto [lw, lh] : rb.pyramidSizes) {
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
        st.shade.mode == ShadingMode::Classified
            ? (4.0 * st.shade.classifiedTiles + double(sizeof(gpu::MaterialTiles)) * st.shade.materialTiles.size()) / double(pixels)
            : 0.0;
    st.bytesWrittenPerPixel = st.rasterWritesPerPixel * st.rasterBytesPerFragment + resolveBytes + classifyBytes;
  }
  if (rb.attributes) {
    const float* a = static_cast<const float*>(attributesReadback.mapped());
    result.attributes.assign(a, a + pixels * ATTRIBUTE_FLOATS);
  }
  if (readIds && options.path == RenderPath::Forward) {  // already (object + 1, triangle)
    const uint32_t* raw = static_cast<const uint32_t*>(idsReadback.mapped());
    result.ids.assign(raw, raw + pixels * 2);
  } else if (readIds) {
    const size_t samples = size_t(options.msaa);  // MSAA: every sample (2 uints each, like wide IDs)
    result.ids.assign(pixels * samples * 2, 0);
    const uint32_t* s = static_cast<const uint32_t*>(frame.statsReadback.mapped());
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
      // The triangle within the draw's LOD level (a cluster draw starts inside it).
      const gpu::DrawCommand& d = dr[slot];
      result.ids[2 * i] = d.firstInstance + 1;
      result.ids[2 * i + 1] = tri + (d.firstIndex - gpuScene.meshTable[gpuScene.objectMesh[d.firstInstance]].lods[drawLod(d)].firstIndex) / 3;
    }
  }

}

}  // namespace visbuf
