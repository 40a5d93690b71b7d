#include "visbuf/render/frame_plan.h"

namespace visbuf {

ShadingMode resolveShading(const FrameOptions& options, const SceneFacts& facts, bool mostlyCovered) {
  if (options.path != RenderPath::Visbuf || options.readAttributes || options.msaa > 1) return ShadingMode::Uber;
  ShadingMode mode = options.shading;
  if (mode == ShadingMode::Auto)
    mode = facts.cpuDevice && mostlyCovered ? ShadingMode::Uber : defaultShadingFor(facts.cpuDevice);
  return mode == ShadingMode::Covered && !facts.coveredListFits ? ShadingMode::Uber : mode;
}

bool microRasterAllowed(const FrameOptions& options, const SceneFacts& facts) {
  // Auto: on for both device types (docs/benchmarks.md, "Software micro-raster"); on a GPU a frame in which it
  // took too little to pay for its merges skips it for a while (FrameHistory::finished).
  const bool asked = options.swRaster != SwRasterMode::Off;
  return asked && options.path == RenderPath::Visbuf && options.msaa == 1 && !options.countOverdraw &&
         facts.microRasterLists && facts.microRasterFits;
}

bool microRasterResolves(const FrameOptions& options) {
  return options.swResolve != SwResolve::Merge;  // Auto: on both device types (FrameOptions::swResolve)
}

bool lightsCulled(const FrameOptions& options, const SceneFacts& facts) {
  return options.path == RenderPath::Visbuf && options.tiledLights && facts.pointLights;
}

FramePlan planFrame(const FrameOptions& options, const SceneFacts& facts, const FrameHistory& history, bool handsOn) {
  FramePlan p;
  p.gpuCulled = options.path != RenderPath::Forward;  // visbuf and G-buffer: cull pass + draw lists
  p.frozen = p.gpuCulled && options.freezeCulling && history.haveDraws;
  p.cull = p.frozen ? history.lastCull : options.cull;
  p.occlusionFrame = p.gpuCulled && !p.frozen && options.cull == CullMode::Occlusion;
  // The micro-raster this frame (a frozen frame redraws what its frame routed).
  p.swOn = p.frozen ? history.lastSwOn : microRasterAllowed(options, facts) && history.swSkipFrames == 0;
  p.usePyramid = p.occlusionFrame &&
                 (options.readPyramid || !(options.skipUselessPyramid && history.pyramidSkipFrames > 0));
  p.lateOnly = p.occlusionFrame && !p.usePyramid;
  p.lightsCulled = lightsCulled(options, facts);
  p.readAttributes = options.readAttributes && p.gpuCulled;  // G-buffer: position and depth only
  p.msaa = options.msaa > 1;
  p.shading = resolveShading(options, facts, history.mostlyCovered);
  p.coveredPixels = p.shading == ShadingMode::Covered;  // (resolveShading: visbuf, single-sampled, no attributes)
  p.clusters = p.gpuCulled && !p.frozen && options.clusters && facts.clusters && p.cull != CullMode::None;
  p.earlyClusterOcclusion = p.clusters && p.usePyramid && options.earlyClusterOcclusion && history.pyramidBuilt;
  // Merge-free micro-raster: what its merges wrote is read only by the pyramid and the shading, which resolve it.
  p.swResolved = p.swOn && microRasterResolves(options) && options.path == RenderPath::Visbuf && !p.msaa &&
                 p.shading != ShadingMode::Classified && !p.lightsCulled && !facts.transparency && !options.readIds &&
                 !handsOn;
  return p;
}

void FrameHistory::recorded(const FramePlan& plan) {
  if (!plan.gpuCulled) return;
  haveDraws = true;
  lastCull = plan.cull;
  if (!plan.frozen) {
    lastSwOn = plan.swOn;
    pyramidBuilt = plan.usePyramid;
  }
}

void FrameHistory::shaded(uint64_t coveredPixels, uint64_t pixels) {
  if (pixels == 0) return;
  const double share = double(coveredPixels) / double(pixels);
  if (share >= kUberFromCoverage)
    mostlyCovered = true;
  else if (share < kCoveredBelowCoverage)
    mostlyCovered = false;
}

void FrameHistory::finished(const FramePlan& plan, const FrameOptions& options, bool cpuDevice, uint64_t swTriangles,
                            uint32_t drawsEarly, uint32_t occlusionCulled, const PyramidCost& cost) {
  if (!plan.gpuCulled) return;
  // "Skip what the scene does not need": a frame whose micro-raster took nothing (Auto on a GPU: less than pays
  // for its merges) routes everything to the hardware raster for a while, then probes again.
  if (!plan.frozen) {
    const uint64_t worth = options.swRaster == SwRasterMode::Auto && !cpuDevice ? kGpuSwMinTriangles : 1;
    if (plan.swOn)
      swSkipFrames = swTriangles < worth ? kSwProbeInterval : 0;
    else if (swSkipFrames > 0)
      --swSkipFrames;
  }
  // A pyramid that hid nothing, or so little that drawing it would have cost the raster less than half the pyramid's
  // own time (lavapipe, 10k kittens in the peer's view: 20 objects hidden, about 0.2 ms of raster, for a 4 ms
  // pyramid), is not built again for a while; the objects it hid are drawn meanwhile. Only a pyramid built from a
  // non-empty early phase is evidence (a first frame or a cut has none). The probe frame tests every object in the
  // frustum against the pyramid, those the early phase drew included, so it counts what the pyramid would hide.
  if (plan.usePyramid) {
    const double saved = cost.rasterMsPerObject * occlusionCulled;
    const bool costsMore = cost.rasterMsPerObject > 0.0 && cost.pyramidMs > kPyramidPayFactor * saved;
    const bool useless = occlusionCulled == 0 || costsMore;
    pyramidSkipFrames = options.skipUselessPyramid && drawsEarly > 0 && useless ? kPyramidProbeInterval : 0;
  } else if (pyramidSkipFrames > 0) {
    --pyramidSkipFrames;
  }
}

}  // namespace visbuf
