// planFrame(options, scene facts, history): every decision of a frame from what it is given, and the history that
// finished frames leave for later plans (skip a pyramid or micro-raster that did nothing, redraw frozen lists).
#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

#include "visbuf/passes/depth_pyramid_pass.h"
#include "visbuf/render/frame_plan.h"
#include "visbuf/shared/config.h"

using namespace visbuf;

namespace {

SceneFacts gpuFacts() { return {.cpuDevice = false, .microRasterLists = true, .microRasterFits = true, .pointLights = true}; }

}  // namespace

TEST(FramePlan, PathsDecideCullingShadingAndLights) {
  FrameOptions fo;
  const FrameHistory none;
  FramePlan p = planFrame(fo, gpuFacts(), none);
  EXPECT_TRUE(p.gpuCulled);
  EXPECT_TRUE(p.swOn);
  EXPECT_TRUE(p.lightsCulled);
  EXPECT_EQ(p.shading, ShadingMode::Uber) << "GPUs shade with the ubershader by default";
  EXPECT_FALSE(p.coveredPixels);
  SceneFacts cpu = gpuFacts();
  cpu.cpuDevice = true;
  p = planFrame(fo, cpu, none);
  EXPECT_EQ(p.shading, ShadingMode::Covered) << "CPU devices shade the covered pixels only";
  EXPECT_TRUE(p.coveredPixels);
  SceneFacts huge = cpu;
  huge.coveredListFits = false;  // a frame whose covered-pixel list outgrows its texel view
  EXPECT_EQ(planFrame(fo, huge, none).shading, ShadingMode::Uber) << "Auto";
  fo.shading = ShadingMode::Covered;
  EXPECT_EQ(planFrame(fo, huge, none).shading, ShadingMode::Uber) << "asked for";
  EXPECT_EQ(planFrame(fo, cpu, none).shading, ShadingMode::Covered);
  fo.shading = ShadingMode::Auto;
  fo.readAttributes = true;  // the attribute record exists in the ubershader only
  p = planFrame(fo, cpu, none);
  EXPECT_EQ(p.shading, ShadingMode::Uber);
  EXPECT_TRUE(p.readAttributes);

  fo = FrameOptions{};
  fo.path = RenderPath::Forward;
  fo.readAttributes = true;
  p = planFrame(fo, gpuFacts(), none);
  EXPECT_FALSE(p.gpuCulled);
  EXPECT_FALSE(p.swOn);
  EXPECT_FALSE(p.lightsCulled) << "the forward path lights every pixel with every light";
  EXPECT_FALSE(p.readAttributes);
  EXPECT_FALSE(p.usePyramid);

  fo = FrameOptions{};
  fo.tiledLights = false;
  EXPECT_FALSE(planFrame(fo, gpuFacts(), none).lightsCulled);
  SceneFacts dark = gpuFacts();
  dark.pointLights = false;
  EXPECT_FALSE(planFrame(FrameOptions{}, dark, none).lightsCulled);
}

// Auto shading on a CPU device follows the last frame's coverage, with a band between the two thresholds where it
// keeps its choice; a GPU, an explicit mode and the cases only the ubershader serves are not affected.
TEST(FramePlan, AutoShadingOnACpuFollowsTheLastFramesCoverage) {
  SceneFacts cpu = gpuFacts();
  cpu.cpuDevice = true;
  const FrameOptions fo;
  FrameHistory h;
  const uint64_t pixels = 1000;
  auto shadingAfter = [&](uint64_t covered) {
    h.shaded(covered, pixels);
    return planFrame(fo, cpu, h).shading;
  };
  EXPECT_EQ(planFrame(fo, cpu, h).shading, ShadingMode::Covered) << "no frame yet";
  EXPECT_EQ(shadingAfter(200), ShadingMode::Covered);
  EXPECT_EQ(shadingAfter(640), ShadingMode::Covered) << "below the upper threshold";
  EXPECT_EQ(shadingAfter(650), ShadingMode::Uber) << "at it";
  EXPECT_FALSE(planFrame(fo, cpu, h).coveredPixels);
  EXPECT_EQ(shadingAfter(560), ShadingMode::Uber) << "inside the band: kept";
  EXPECT_EQ(shadingAfter(549), ShadingMode::Covered) << "below the lower threshold";
  EXPECT_EQ(shadingAfter(600), ShadingMode::Covered) << "inside the band: kept";
  EXPECT_EQ(shadingAfter(1000), ShadingMode::Uber);
  h.shaded(0, 0);  // no pixels: nothing learnt
  EXPECT_TRUE(h.mostlyCovered);
  EXPECT_EQ(planFrame(fo, gpuFacts(), h).shading, ShadingMode::Uber) << "a GPU: uber whatever the coverage";
  FrameOptions covered = fo;
  covered.shading = ShadingMode::Covered;
  EXPECT_EQ(planFrame(covered, cpu, h).shading, ShadingMode::Covered) << "asked for";
  EXPECT_EQ(shadingAfter(0), ShadingMode::Covered);
  FrameOptions msaa = fo;
  msaa.msaa = 4;
  EXPECT_EQ(planFrame(msaa, cpu, h).shading, ShadingMode::Uber) << "MSAA: the ubershader only";
}

TEST(FramePlan, MicroRasterOnlyWhereItCanTakeDraws) {
  const FrameHistory none;
  FrameOptions fo;
  EXPECT_TRUE(planFrame(fo, gpuFacts(), none).swOn);
  fo.swRaster = SwRasterMode::Off;
  EXPECT_FALSE(planFrame(fo, gpuFacts(), none).swOn);
  fo = FrameOptions{};
  fo.msaa = 4;
  EXPECT_FALSE(planFrame(fo, gpuFacts(), none).swOn) << "single-sampled only";
  fo = FrameOptions{};
  fo.countOverdraw = true;
  EXPECT_FALSE(planFrame(fo, gpuFacts(), none).swOn) << "the overdraw count counts hardware raster writes";
  SceneFacts f = gpuFacts();
  f.microRasterLists = false;
  EXPECT_FALSE(planFrame(FrameOptions{}, f, none).swOn);
  f = gpuFacts();
  f.microRasterFits = false;
  EXPECT_FALSE(planFrame(FrameOptions{}, f, none).swOn);
  FrameHistory skipping;
  skipping.swSkipFrames = 3;
  EXPECT_FALSE(planFrame(FrameOptions{}, gpuFacts(), skipping).swOn);
}

TEST(FramePlan, HistorySkipsAUselessPyramidThenProbesAgain) {
  FrameOptions fo;
  fo.cull = CullMode::Occlusion;
  FrameHistory h;
  FramePlan p = planFrame(fo, gpuFacts(), h);
  ASSERT_TRUE(p.occlusionFrame);
  ASSERT_TRUE(p.usePyramid);
  h.recorded(p);
  // A first frame (no early draws) is no evidence; a frame with early draws whose pyramid hid nothing is.
  h.finished(p, fo, false, 0, /*drawsEarly=*/0, /*occlusionCulled=*/0);
  EXPECT_EQ(h.pyramidSkipFrames, 0u);
  h.finished(p, fo, false, 0, 100, 0);
  EXPECT_EQ(h.pyramidSkipFrames, kPyramidProbeInterval);
  for (uint32_t i = 0; i < kPyramidProbeInterval; ++i) {
    FramePlan skipped = planFrame(fo, gpuFacts(), h);
    EXPECT_FALSE(skipped.usePyramid) << i;
    FrameOptions read = fo;
    read.readPyramid = true;
    EXPECT_TRUE(planFrame(read, gpuFacts(), h).usePyramid) << "a frame that reads the pyramid back builds it";
    h.finished(skipped, fo, false, 0, 100, 0);
  }
  EXPECT_TRUE(planFrame(fo, gpuFacts(), h).usePyramid) << "probed again";
  h.finished(planFrame(fo, gpuFacts(), h), fo, false, 0, 100, /*occlusionCulled=*/5);
  EXPECT_EQ(h.pyramidSkipFrames, 0u) << "a pyramid that hid something stays";
  h.finished(planFrame(fo, gpuFacts(), h), fo, false, 0, 100, 0);
  h.cut();
  EXPECT_TRUE(planFrame(fo, gpuFacts(), h).usePyramid) << "a cut probes at once";
}

// A pyramid that hid objects worth less raster time than half its own is skipped too; without times (or with a
// pyramid that pays) the count alone decides. Reference: the rule's arithmetic on round figures.
TEST(FramePlan, HistorySkipsAPyramidThatCostsMoreThanItSaves) {
  FrameOptions fo;
  fo.cull = CullMode::Occlusion;
  FrameHistory h;
  const FramePlan p = planFrame(fo, gpuFacts(), h);
  ASSERT_TRUE(p.usePyramid);
  // 20 objects hidden at 1/64 ms of raster each (0.31 ms) by a 4 ms pyramid: skipped.
  const PyramidCost cost{4.0, 1.0 / 64.0};
  h.finished(p, fo, true, 0, 1500, 20, cost);
  EXPECT_EQ(h.pyramidSkipFrames, kPyramidProbeInterval);
  h.cut();
  // 4,000 objects hidden (62.5 ms of raster) by the same pyramid: kept.
  h.finished(p, fo, true, 0, 9000, 4000, cost);
  EXPECT_EQ(h.pyramidSkipFrames, 0u);
  // At the bound, 4 ms against 2 x 128 / 64 ms, the pyramid does not cost more: kept; one object fewer: skipped.
  h.finished(p, fo, true, 0, 9000, 128, cost);
  EXPECT_EQ(h.pyramidSkipFrames, 0u);
  h.finished(p, fo, true, 0, 9000, 127, cost);
  EXPECT_EQ(h.pyramidSkipFrames, kPyramidProbeInterval);
  h.cut();
  // No times measured: the count decides, as before.
  h.finished(p, fo, true, 0, 1500, 20, {});
  EXPECT_EQ(h.pyramidSkipFrames, 0u);
  // Pinned on: never skipped.
  FrameOptions pinned = fo;
  pinned.skipUselessPyramid = false;
  h.finished(p, pinned, true, 0, 1500, 20, cost);
  EXPECT_EQ(h.pyramidSkipFrames, 0u);
}

// A skipped pyramid leaves the late phase alone (over every object, history cleared); a built one, or another
// culling mode, keeps the phases as they are.
TEST(FramePlan, SkippedPyramidRunsTheLatePhaseAlone) {
  FrameOptions fo;
  fo.cull = CullMode::Occlusion;
  FrameHistory h;
  const FramePlan built = planFrame(fo, gpuFacts(), h);
  EXPECT_TRUE(built.usePyramid);
  EXPECT_FALSE(built.lateOnly);
  h.finished(built, fo, true, 0, 1500, 0, {});  // hid nothing: skipped for a while
  ASSERT_EQ(h.pyramidSkipFrames, kPyramidProbeInterval);
  const FramePlan skipped = planFrame(fo, gpuFacts(), h);
  EXPECT_FALSE(skipped.usePyramid);
  EXPECT_TRUE(skipped.lateOnly);
  EXPECT_FALSE(skipped.earlyClusterOcclusion);
  FrameOptions frustum = fo;
  frustum.cull = CullMode::Frustum;
  EXPECT_FALSE(planFrame(frustum, gpuFacts(), h).lateOnly);
  FrameOptions forward = fo;
  forward.path = RenderPath::Forward;
  EXPECT_FALSE(planFrame(forward, gpuFacts(), h).lateOnly);
  // The probe after the interval builds the pyramid again, with both phases.
  for (uint32_t i = 0; i < kPyramidProbeInterval; ++i) h.finished(skipped, fo, true, 0, 0, 0, {});
  EXPECT_FALSE(planFrame(fo, gpuFacts(), h).lateOnly);
}

// The early phase guesses with the pyramid the previous frame built: only after a frame that built one, never after
// a cut or a new size (its pyramid shows another view), and only with clusters and occlusion culling.
TEST(FramePlan, EarlyClusterOcclusionNeedsLastFramesPyramid) {
  FrameOptions fo;
  fo.cull = CullMode::Occlusion;
  SceneFacts facts = gpuFacts();
  facts.clusters = true;
  FrameHistory h;
  FramePlan p = planFrame(fo, facts, h);
  ASSERT_TRUE(p.clusters && p.usePyramid);
  EXPECT_FALSE(p.earlyClusterOcclusion) << "a first frame has no pyramid of its own";
  h.recorded(p);
  EXPECT_TRUE(planFrame(fo, facts, h).earlyClusterOcclusion);
  FrameOptions off = fo;
  off.earlyClusterOcclusion = false;
  EXPECT_FALSE(planFrame(off, facts, h).earlyClusterOcclusion);
  off = fo;
  off.clusters = false;
  EXPECT_FALSE(planFrame(off, facts, h).earlyClusterOcclusion);
  h.cut();
  EXPECT_FALSE(planFrame(fo, facts, h).earlyClusterOcclusion) << "after a cut the pyramid shows another view";
  h.recorded(planFrame(fo, facts, h));
  EXPECT_TRUE(planFrame(fo, facts, h).earlyClusterOcclusion);
  FrameOptions frustum = fo;
  frustum.cull = CullMode::Frustum;
  h.recorded(planFrame(frustum, facts, h));  // builds no pyramid
  EXPECT_FALSE(planFrame(fo, facts, h).earlyClusterOcclusion) << "the last frame built no pyramid";
}

TEST(FramePlan, HistorySkipsAMicroRasterThatDoesNotPayOnAGpu) {
  FrameOptions fo;
  FrameHistory h;
  FramePlan p = planFrame(fo, gpuFacts(), h);
  ASSERT_TRUE(p.swOn);
  h.finished(p, fo, /*cpuDevice=*/false, kGpuSwMinTriangles - 1, 10, 0);
  EXPECT_EQ(h.swSkipFrames, kSwProbeInterval) << "Auto on a GPU: too few triangles to pay for the merges";
  FrameHistory cpu;
  cpu.finished(p, fo, /*cpuDevice=*/true, 1, 10, 0);
  EXPECT_EQ(cpu.swSkipFrames, 0u) << "on a CPU device one triangle pays";
  cpu.finished(p, fo, true, 0, 10, 0);
  EXPECT_EQ(cpu.swSkipFrames, kSwProbeInterval) << "nothing taken: skipped";
  FrameOptions on = fo;
  on.swRaster = SwRasterMode::On;
  FrameHistory asked;
  asked.finished(planFrame(on, gpuFacts(), asked), on, false, 1, 10, 0);
  EXPECT_EQ(asked.swSkipFrames, 0u) << "On: whenever it takes anything";
}

TEST(FramePlan, FrozenFramesRedrawTheListsTheyFroze) {
  FrameOptions fo;
  fo.cull = CullMode::Occlusion;
  fo.freezeCulling = true;
  FrameHistory h;
  EXPECT_FALSE(planFrame(fo, gpuFacts(), h).frozen) << "nothing to freeze before a culled frame";
  FrameOptions culled;
  culled.cull = CullMode::Frustum;
  culled.swRaster = SwRasterMode::Off;
  h.recorded(planFrame(culled, gpuFacts(), h));
  const FramePlan p = planFrame(fo, gpuFacts(), h);
  EXPECT_TRUE(p.frozen);
  EXPECT_EQ(p.cull, CullMode::Frustum) << "the frozen lists' culling";
  EXPECT_FALSE(p.swOn) << "the frozen frame routed nothing to the micro-raster";
  EXPECT_FALSE(p.occlusionFrame);
  EXPECT_FALSE(p.usePyramid);
  h.recorded(p);
  EXPECT_EQ(h.lastCull, CullMode::Frustum);
}

// The pyramid's dispatches write every level after 0 exactly once, each reading the level the one before stopped
// at, with that level's valid size (ceil(size / 2^k)). Derived by hand for PYRAMID_REDUCTIONS = 3 (a dispatch reduces
// at most 3 levels), halving with rounding up until both sides are 1:
//   1024x768: 1024x768, 512x384, 256x192, 128x96, 64x48, 32x24, 16x12, 8x6, 4x3, 2x2, 1x1: 11 levels (0..10);
//     dispatches from level 0 (3 levels), 3 (128x96, 3), 6 (16x12, 3), 9 (2x2, the last 1).
//   1920x1080: 1920x1080, 960x540, 480x270, 240x135, 120x68, 60x34, 30x17, 15x9, 8x5, 4x3, 2x2, 1x1: 12 levels;
//     dispatches from 0 (3), 3 (240x135, 3), 6 (30x17, 3), 9 (4x3, the last 2).
//   1x1: one level, nothing to reduce: one dispatch of 0 reductions (it may still copy the depth into level 0).
//   3x5: 3x5, 2x3, 1x2, 1x1: 4 levels; one dispatch of 3.
//   37x11: 37x11, 19x6, 10x3, 5x2, 3x1, 2x1, 1x1: 7 levels; from 0 (3), from 3 (5x2, 3).
//   32768x1: 2^15 wide: 16 levels; from 0, 3 (4096x1), 6 (512x1), 9 (64x1), 12 (8x1), 3 each.
TEST(DepthPyramid, DispatchesWriteEveryLevelOnce) {
  static_assert(PYRAMID_REDUCTIONS == 3, "the dispatches below are derived for 3 reductions per dispatch");
  struct Case {
    uint32_t width, height, levels;
    std::vector<std::array<uint32_t, 4>> dispatches;  // source level, its valid width and height, reductions
  };
  const Case cases[] = {
      {1024, 768, 11, {{0, 1024, 768, 3}, {3, 128, 96, 3}, {6, 16, 12, 3}, {9, 2, 2, 1}}},
      {1920, 1080, 12, {{0, 1920, 1080, 3}, {3, 240, 135, 3}, {6, 30, 17, 3}, {9, 4, 3, 2}}},
      {1, 1, 1, {{0, 1, 1, 0}}},
      {3, 5, 4, {{0, 3, 5, 3}}},
      {37, 11, 7, {{0, 37, 11, 3}, {3, 5, 2, 3}}},
      {32768, 1, 16, {{0, 32768, 1, 3}, {3, 4096, 1, 3}, {6, 512, 1, 3}, {9, 64, 1, 3}, {12, 8, 1, 3}}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::to_string(c.width) + "x" + std::to_string(c.height));
    EXPECT_EQ(passes::pyramidLevelCount(c.width, c.height), c.levels);
    const auto dispatches = passes::pyramidDispatches(c.width, c.height);
    ASSERT_EQ(dispatches.size(), c.dispatches.size());
    for (size_t i = 0; i < dispatches.size(); ++i) {
      EXPECT_EQ(dispatches[i].source, c.dispatches[i][0]) << "dispatch " << i;
      EXPECT_EQ(dispatches[i].width, c.dispatches[i][1]) << "dispatch " << i;
      EXPECT_EQ(dispatches[i].height, c.dispatches[i][2]) << "dispatch " << i;
      EXPECT_EQ(dispatches[i].reductions, c.dispatches[i][3]) << "dispatch " << i;
    }
  }
}

// The micro-raster is resolved by the pyramid and the shading (no merges) only where nothing else reads the ID target
// or the depth; Auto resolves on both device types.
TEST(FramePlan, MicroRasterResolvedOnlyWhereNothingElseReadsTheTarget) {
  SceneFacts gpu = gpuFacts();
  gpu.pointLights = false;
  SceneFacts cpu = gpu;
  cpu.cpuDevice = true;
  const FrameHistory none;
  FrameOptions fo;
  EXPECT_TRUE(planFrame(fo, gpu, none).swResolved) << "Auto on a GPU";
  EXPECT_TRUE(planFrame(fo, cpu, none).swResolved) << "Auto on a CPU device";
  fo.swResolve = SwResolve::Merge;
  EXPECT_FALSE(planFrame(fo, cpu, none).swResolved);
  fo.swResolve = SwResolve::Shading;
  EXPECT_TRUE(planFrame(fo, cpu, none).swResolved);
  EXPECT_FALSE(planFrame(fo, gpu, none, /*handsOn=*/true).swResolved) << "record(): the host reads IDs and depth";
  auto with = [&](auto change, const SceneFacts& facts) {
    FrameOptions o = fo;
    change(o);
    return planFrame(o, facts, none).swResolved;
  };
  EXPECT_FALSE(with([](FrameOptions& o) { o.swResolve = SwResolve::Merge; }, gpu));
  EXPECT_FALSE(with([](FrameOptions& o) { o.readIds = true; }, gpu)) << "IDs read back from the target";
  EXPECT_FALSE(with([](FrameOptions& o) { o.shading = ShadingMode::Classified; }, gpu)) << "classify reads the IDs";
  EXPECT_FALSE(with([](FrameOptions& o) { o.swRaster = SwRasterMode::Off; }, gpu)) << "nothing to resolve";
  EXPECT_TRUE(with([](FrameOptions& o) { o.readAttributes = true; }, gpu)) << "the ubershader resolves too";
  EXPECT_TRUE(with([](FrameOptions& o) { o.readPyramid = true; }, gpu)) << "the pyramid resolves";
  SceneFacts lights = gpu;
  lights.pointLights = true;
  EXPECT_FALSE(with([](FrameOptions&) {}, lights)) << "the light cull reads the depth";
  SceneFacts blend = gpu;
  blend.transparency = true;
  EXPECT_FALSE(with([](FrameOptions&) {}, blend)) << "the transparency pass tests against the depth";
}
