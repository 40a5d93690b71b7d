// Every decision of one frame, taken once before anything is recorded: planFrame(options, scene facts, history).
// The frame script (renderer.cpp) declares its passes from the plan; nothing it records decides anything else.
// What later frames decide from (a pyramid that hid nothing, a micro-raster that took nothing, the draw lists a
// frozen frame redraws) is FrameHistory, updated when a frame is recorded and when its counters come back.
#pragma once

#include <cstdint>

#include "visbuf/render/renderer.h"

namespace visbuf {

struct FramePlan {
  bool gpuCulled = false;       // visbuf and G-buffer: cull pass and draw lists; forward: CPU culling
  bool frozen = false;          // redraw the last culled frame's draw lists (freezeCulling)
  CullMode cull = CullMode::None;  // in effect (a frozen frame: the frozen frame's)
  bool occlusionFrame = false;  // occlusion culling runs this frame (not frozen)
  bool usePyramid = false;      // build the depth pyramid (and run the late occlusion test against it)
  // An occlusion frame without a pyramid (skipped: it hid nothing lately) runs its late phase alone, over every
  // object with the history cleared: exact without a pyramid, and it keeps the visible list for the next probe,
  // while the early phase's passes (cull, raster, micro-raster) and their fixed costs go.
  bool lateOnly = false;
  bool swOn = false;            // route small objects to the micro-raster
  bool lightsCulled = false;    // tile light lists
  bool readAttributes = false;  // the shading pass writes the attribute record
  bool msaa = false;
  ShadingMode shading = ShadingMode::Uber;
  // The ubershader over the covered pixels only (covered_pixels.comp lists them): single-sampled visbuf frames
  // without the attribute record.
  bool coveredPixels = false;
  // Objects drawn by the hardware raster are expanded into clusters (the cull pass's CULL_CLUSTERS dispatch).
  bool clusters = false;
  // The early phase's cluster dispatch tests against the pyramid the previous frame built and defers what it hides
  // to the late phase's retest (CULL_CLUSTER_RETEST).
  bool earlyClusterOcclusion = false;
  // The micro-raster's fragments are not merged into the ID target and depth: the pyramid and the shading take the
  // nearer of the two per pixel (FrameData.swResolve). Only where nothing else reads the target or the depth: no
  // IDs read back or handed to a host, no light culling, transparency or classification, single-sampled.
  bool swResolved = false;
};

// What the renderer's scene and device are, as far as a plan depends on them.
struct SceneFacts {
  bool cpuDevice = false;         // lavapipe and the like: covered-pixel shading by default
  bool microRasterLists = false;  // some draw list the micro-raster may take (opaque, uncapped)
  bool microRasterFits = false;   // its 64-bit per-pixel buffer fits one storage-buffer range and texel view at this size
  bool pointLights = false;       // the scene has punctual lights
  bool clusters = false;          // some LOD level has clusters and some draw list a cluster reserve
  bool transparency = false;      // the scene has BLEND objects (the transparency pass tests against the depth)
  bool coveredListFits = true;    // the covered-pixel list is readable at this size (its texel view, where used, holds it)
};

// A pyramid or micro-raster that did nothing is skipped for this many frames, then probed again.
inline constexpr uint32_t kPyramidProbeInterval = 16;
inline constexpr uint32_t kSwProbeInterval = 16;
// Auto on a GPU: the micro-raster pays for its two full-screen merges from about this many triangles.
inline constexpr uint64_t kGpuSwMinTriangles = 262144;
// A pyramid that hid something is skipped too when it cost more than this many times what the raster would have paid
// for the objects it hid.
inline constexpr double kPyramidPayFactor = 2.0;

// Auto shading on a CPU device: the covered-pixel list pays where much of the frame is empty (lavapipe, peer view
// of 30k kittens, 46 % covered: the ubershader 1.17x the covered shading's time), the ubershader where little is
// (72 %: 0.92x; 87 %: 0.87x; 100 %: 0.82x), so frames switch to it from this share of the last frame's pixels and
// back below the lower one.
inline constexpr double kUberFromCoverage = 0.65;
inline constexpr double kCoveredBelowCoverage = 0.55;

// A finished frame's GPU times, as far as the pyramid's worth goes: the pyramid pass, and the raster's time (hardware
// raster and micro-raster, both phases) per object it drew. Zero: not measured (the pyramid is judged by its count).
struct PyramidCost {
  double pyramidMs = 0.0;
  double rasterMsPerObject = 0.0;
};

// What earlier frames left that a frame's plan depends on.
struct FrameHistory {
  bool haveDraws = false;               // a GPU-culled frame has filled the draw lists (freezeCulling reuses them)
  CullMode lastCull = CullMode::Frustum;  // the culling those draw lists were made with
  bool lastSwOn = false;                // ... and whether they routed draws to the micro-raster
  uint32_t swSkipFrames = 0;            // frames before the micro-raster is probed again
  uint32_t pyramidSkipFrames = 0;       // frames before the pyramid is built again
  bool pyramidBuilt = false;            // the last GPU-culled frame built the pyramid (since the last cut or resize)
  // The last finished single-sampled visbuf frame showed something in most pixels (kUberFromCoverage; it stays so
  // until a frame shows less than kCoveredBelowCoverage): Auto shading on a CPU device takes the ubershader then.
  bool mostlyCovered = false;

  // A frame recorded with `plan`.
  void recorded(const FramePlan& plan);
  // The counters of a finished GPU-culled frame recorded with `plan` and `options`: whether its micro-raster and
  // pyramid paid (swTriangles: the micro-raster's triangles; drawsEarly, occlusionCulled: the cull's counts; cost:
  // the frame's times).
  void finished(const FramePlan& plan, const FrameOptions& options, bool cpuDevice, uint64_t swTriangles,
                uint32_t drawsEarly, uint32_t occlusionCulled, const PyramidCost& cost = {});
  // The pixels a finished single-sampled visbuf frame shaded (it showed something there), of `pixels`.
  void shaded(uint64_t coveredPixels, uint64_t pixels);
  // A cut or a new size: the pyramid is probed again at once.
  void cut() {
    pyramidSkipFrames = 0;
    pyramidBuilt = false;  // (what it holds is of another view or size: no guess for the next early phase)
  }
};

// The shading mode a visbuf frame uses (Auto resolved by the device type and, on a CPU device, whether the last
// frame was mostly covered: FrameHistory::mostlyCovered; the attribute record and MSAA exist in the ubershader only);
// other paths: Uber.
ShadingMode resolveShading(const FrameOptions& options, const SceneFacts& facts, bool mostlyCovered = false);
// Whether a frame with these options may route small objects to the micro-raster: asked for (Auto: on), the visbuf
// path, single-sampled, no overdraw count (it counts hardware raster writes), a list it may take, a buffer that fits.
bool microRasterAllowed(const FrameOptions& options, const SceneFacts& facts);
// Whether the micro-raster of a frame with these options is resolved rather than merged where the frame allows it
// (FrameOptions::swResolve; FramePlan::swResolved says whether the frame does).
bool microRasterResolves(const FrameOptions& options);
// Whether a frame builds tile light lists: visbuf path, tiled lights asked for, punctual lights to cull.
bool lightsCulled(const FrameOptions& options, const SceneFacts& facts);

// handsOn: the frame's IDs and depth go to a host (Renderer::record), which may read them.
FramePlan planFrame(const FrameOptions& options, const SceneFacts& facts, const FrameHistory& history,
                    bool handsOn = false);

}  // namespace visbuf
