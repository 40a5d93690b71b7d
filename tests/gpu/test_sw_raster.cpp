// The software micro-raster (sw_raster_pass): small objects rasterised in compute and merged into the same ID
// target must give the hardware raster's image (the reference: same clip positions, same 1/256-pixel snapping,
// same top-left rule), must never be changed by culling, and must refuse what it cannot do.
#include <algorithm>
#include <array>
#include <cstdio>
#include <tuple>

#include <glm/gtc/matrix_transform.hpp>

#include "gpu_test_util.h"
#include "visbuf/scene/generate.h"

using namespace visbuf;

namespace {

// A dense field of small torus knots (1,152 triangles each) seen from outside: most objects cover a few pixels.
Scene smallObjectField(uint32_t objects) {
  FieldParams p;
  p.objects = objects;
  p.seed = 11;
  p.mesh = makeTorusKnot(48, 12);
  return makeFieldScene(p).value();
}

Camera outsideCamera(double t) {
  Camera c;
  const double r = 520.0 - 200.0 * t;
  c.position = {r * std::sin(t * 2.0), 60.0 * std::sin(t * 3.0), r * std::cos(t * 2.0)};
  c.target = glm::dvec3(0.0);
  c.nearPlane = 0.1;
  return c;
}

struct IdDiff {
  size_t pixels = 0, covered = 0, otherTriangle = 0, otherObject = 0;
};
IdDiff compareIds(const FrameResult& a, const FrameResult& b) {
  IdDiff d;
  d.pixels = a.ids.size() / 2;
  for (size_t p = 0; p < a.ids.size(); p += 2) {
    d.covered += b.ids[p] != 0;
    if (a.ids[p] != b.ids[p])
      ++d.otherObject;
    else if (a.ids[p + 1] != b.ids[p + 1])
      ++d.otherTriangle;
  }
  return d;
}

}  // namespace

// Against the hardware raster of the same frames: the two may disagree only where a pixel centre lies within the
// float rounding of the viewport transform of a shared edge (then the neighbouring triangle of the same surface
// takes it) or where two surfaces are within a depth ulp (SwRaster.AnimatedInstancesMatchHardwareRaster judges
// each such pixel against the exact geometry); measured on lavapipe: 2 and 4 of 518,400 pixels, 60.2 dB over all
// pixels (the few pixels showing another object dominate it). Bounds: 0.05 % of pixels with another triangle,
// 0.01 % with another object, colour PSNR >= 50 dB.
GPU_TEST(SwRaster, MatchesHardwareRaster) {
  Scene scene = smallObjectField(20000);
  auto renderer = Renderer::create(dev, scene, {.width = 480, .height = 270});
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  FrameOptions sw, hw;
  sw.readIds = hw.readIds = true;
  sw.swRaster = SwRasterMode::On;
  hw.swRaster = SwRasterMode::Off;
  sw.swRasterPixels = 48.0f;
  sw.cull = hw.cull = CullMode::Frustum;  // the same draws in both (occlusion's history would differ frame to frame)
  sw.clusters = hw.clusters = false;      // (the micro-raster's clusters: Clusters.MicroRasterClustersMatchHardwareRaster)
  size_t routed = 0, drawn = 0;
  IdDiff total;
  double worstPsnr = 1e9;
  for (int i = 0; i < 4; ++i) {
    const Camera cam = outsideCamera(i / 4.0);
    auto a = (*renderer)->renderFrame(cam, sw);
    auto b = (*renderer)->renderFrame(cam, hw);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_TRUE(a->stats.sw.on);
    EXPECT_FALSE(b->stats.sw.on);
    EXPECT_EQ(b->stats.sw.draws, 0u);
    EXPECT_EQ(a->stats.sw.oversize, 0u);
    EXPECT_EQ(a->stats.cull.drawsRendered, b->stats.cull.drawsRendered);
    EXPECT_EQ(a->stats.trianglesDrawn, b->stats.trianglesDrawn);
    routed += a->stats.sw.draws;
    drawn += a->stats.cull.drawsRendered;
    const IdDiff d = compareIds(a.value(), b.value());
    total.pixels += d.pixels;
    total.covered += d.covered;
    total.otherTriangle += d.otherTriangle;
    total.otherObject += d.otherObject;
    worstPsnr = std::min(worstPsnr, compareColor(a->color, b->color).psnr);
    test::saveOnFailure("sw_raster_" + std::to_string(i), a.value(), b.value());
  }
  std::printf("micro-raster took %zu of %zu draws; vs hardware: %zu pixels another triangle, %zu another object of "
              "%zu (%zu covered); worst PSNR %.1f dB\n",
              routed, drawn, total.otherTriangle, total.otherObject, total.pixels, total.covered, worstPsnr);
  EXPECT_GT(routed, drawn / 2) << "the scene must exercise the micro-raster";
  EXPECT_GT(total.covered, total.pixels / 8);
  EXPECT_LE(total.otherTriangle, total.pixels / 2000);
  EXPECT_LE(total.otherObject, total.pixels / 10000);
  EXPECT_GE(worstPsnr, 50.0);
}

// Coincident triangles (every triangle of the mesh listed twice, as some exported assets have): the depths tie
// exactly, and the hardware raster's depth test keeps the first drawn. The micro-raster must keep the same one (the
// lower triangle of the draw, the lower draw slot): no pixel may show the other copy of the same triangle.
GPU_TEST(SwRaster, CoincidentTrianglesKeepTheFirstInDrawOrder) {
  FieldParams p;
  p.objects = 20000;
  p.seed = 11;
  p.mesh = makeTorusKnot(32, 12);  // 768 triangles, 1,536 listed: within SW_RASTER_MAX_TRIANGLES
  const std::vector<uint32_t> once = p.mesh->indices;
  p.mesh->indices.insert(p.mesh->indices.end(), once.begin(), once.end());
  Scene scene = makeFieldScene(p).value();
  auto renderer = Renderer::create(dev, scene, {.width = 480, .height = 270});
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  FrameOptions sw;
  sw.readIds = true;
  sw.readColor = false;
  sw.lodErrorPixels = 0.0f;
  sw.cull = CullMode::Frustum;
  sw.swRaster = SwRasterMode::On;
  sw.swRasterPixels = 48.0f;
  FrameOptions hw = sw;
  hw.swRaster = SwRasterMode::Off;
  const Mesh& mesh = scene.meshes.at(scene.objects.at(0).mesh);
  auto corners = [&](uint32_t t) {
    std::array<glm::vec3, 3> c;
    for (uint32_t k = 0; k < 3; ++k) {
      const gpu::Vertex& v = mesh.vertices[mesh.indices[mesh.lods[0].firstIndex + 3 * t + k]];
      c[k] = {v.px, v.py, v.pz};
    }
    std::sort(c.begin(), c.end(), [](const glm::vec3& a, const glm::vec3& b) {
      return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    });
    return c;
  };
  size_t routed = 0, covered = 0, copies = 0, other = 0;
  for (int i = 0; i < 3; ++i) {
    const Camera cam = outsideCamera(i / 3.0);
    auto a = (*renderer)->renderFrame(cam, sw);
    auto b = (*renderer)->renderFrame(cam, hw);
    ASSERT_TRUE(a.ok() && b.ok());
    routed += a->stats.sw.draws;
    for (size_t q = 0; q < a->ids.size(); q += 2) {
      covered += b->ids[q] != 0;
      if (a->ids[q] == b->ids[q] && a->ids[q + 1] == b->ids[q + 1]) continue;
      const bool copy = a->ids[q] == b->ids[q] && corners(a->ids[q + 1]) == corners(b->ids[q + 1]);
      copies += copy;
      other += !copy;
    }
  }
  std::printf("coincident triangles: %zu micro-raster draws, %zu px covered; %zu px show the other copy, %zu another "
              "triangle\n", routed, covered, copies, other);
  EXPECT_GT(routed, 3000u);
  EXPECT_GT(covered, 3u * 480u * 270u / 8u);
  EXPECT_EQ(copies, 0u);
  EXPECT_LE(other, 3u * 480u * 270u / 2000u);  // edge and depth ties, as in MatchesHardwareRaster
}

// Culling never changes the micro-raster's IDs either (LOD off): every frame of a path with a cleared history and a
// resize, frustum and occlusion culling against none, pixel for pixel.
GPU_TEST(SwRaster, IdImageUnchangedByCulling) {
  Scene scene = smallObjectField(6000);
  auto renderer = Renderer::create(dev, scene, {.width = 317, .height = 229});
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  FrameOptions none;
  none.lodErrorPixels = 0.0f;
  none.readColor = false;
  none.readIds = true;
  none.swRaster = SwRasterMode::On;
  none.cull = CullMode::None;
  size_t routed = 0, occluded = 0;
  for (int i = 0; i < 24; ++i) {
    if (i == 12) {
      ASSERT_TRUE((*renderer)->resize(211, 97).ok());
    }
    if (i == 18) (*renderer)->clearHistory();
    const Camera cam = outsideCamera(i / 24.0);
    auto ref = (*renderer)->renderFrame(cam, none);
    ASSERT_TRUE(ref.ok());
    for (CullMode mode : {CullMode::Frustum, CullMode::Occlusion}) {
      FrameOptions o = none;
      o.cull = mode;
      auto a = (*renderer)->renderFrame(cam, o);
      ASSERT_TRUE(a.ok());
      routed += a->stats.sw.draws;
      occluded += a->stats.cull.occlusionCulled;
      const IdDiff d = compareIds(a.value(), ref.value());
      ASSERT_EQ(d.otherObject + d.otherTriangle, 0u) << "frame " << i << " " << cullModeName(mode);
    }
  }
  std::printf("24 frames x {frustum, occlusion} identical to no culling; %zu micro-raster draws, %zu occluded\n",
              routed, occluded);
  EXPECT_GT(routed, 0u);
  EXPECT_GT(occluded, 0u);
}

// Resolved by the pyramid and the shading instead of merged (SwResolve::Shading): the same frames give the same
// colour, depth pyramid and attribute record, bit for bit, with both shading dispatches (every pixel, and the
// covered-pixel list that marks the micro-raster's pixels), with 32- and 64-bit IDs, and record no merge pass. A
// frame that reads IDs back merges anyway. Two renderers per ID width, so that each frame's occlusion history is its
// own path's.
GPU_TEST(SwRaster, ResolvedInShadingMatchesMerged) {
  Scene scene = smallObjectField(20000);
  auto hasMerge = [](const FrameResult& f) {
    return std::any_of(f.stats.graph.passMs.begin(), f.stats.graph.passMs.end(),
                       [](const auto& p) { return p.first.rfind("sw merge", 0) == 0; });
  };
  size_t swFrames = 0, frames = 0;
  for (bool wide : {false, true})
  for (ShadingMode shading : {ShadingMode::Covered, ShadingMode::Uber}) {
    const RendererConfig config{.width = 480, .height = 270, .forceWideIds = wide};
    auto merged = Renderer::create(dev, scene, config);
    auto resolved = Renderer::create(dev, scene, config);
    ASSERT_TRUE(merged.ok() && resolved.ok());
    for (int i = 0; i < (wide ? 3 : 6); ++i) {
      FrameOptions m;
      m.swRaster = SwRasterMode::On;
      m.swRasterPixels = 48.0f;
      m.shading = shading;
      m.readPyramid = true;
      m.readAttributes = shading == ShadingMode::Uber && i % 2 == 1;  // (the ubershader's attribute variant)
      m.swResolve = SwResolve::Merge;
      FrameOptions r = m;
      r.swResolve = SwResolve::Shading;
      const Camera cam = outsideCamera(i / 6.0);
      auto a = (*merged)->renderFrame(cam, m);
      auto b = (*resolved)->renderFrame(cam, r);
      ASSERT_TRUE(a.ok() && b.ok());
      ASSERT_TRUE(a->stats.sw.on && b->stats.sw.on);
      EXPECT_FALSE(a->stats.sw.resolved);
      EXPECT_TRUE(b->stats.sw.resolved);
      EXPECT_TRUE(hasMerge(a.value()));
      EXPECT_FALSE(hasMerge(b.value()));
      EXPECT_EQ(a->stats.shade.mode, shading);
      EXPECT_EQ(b->stats.ids.wide, wide);
      EXPECT_EQ(a->stats.trianglesDrawn, b->stats.trianglesDrawn);
      EXPECT_EQ(a->stats.coveredPixels, b->stats.coveredPixels);
      ASSERT_EQ(a->color.size(), b->color.size());
      size_t colourDiffs = 0;
      for (size_t k = 0; k < a->color.size(); ++k) colourDiffs += a->color[k] != b->color[k];
      EXPECT_EQ(colourDiffs, 0u) << shadingModeName(shading) << (wide ? " wide" : "") << " frame " << i;
      ASSERT_EQ(a->pyramid.size(), b->pyramid.size());
      ASSERT_FALSE(a->pyramid.empty());
      for (size_t l = 0; l < a->pyramid.size(); ++l)
        EXPECT_TRUE(a->pyramid[l].depth == b->pyramid[l].depth) << "pyramid level " << l << " frame " << i;
      EXPECT_TRUE(a->attributes == b->attributes) << "frame " << i;
      swFrames += b->stats.sw.triangles > 0;
      ++frames;
    }
  }
  EXPECT_EQ(swFrames, frames) << "every frame's micro-raster drew something";
  auto resolved = Renderer::create(dev, scene, {.width = 480, .height = 270});
  ASSERT_TRUE(resolved.ok());
  FrameOptions ids;
  ids.swRaster = SwRasterMode::On;
  ids.swResolve = SwResolve::Shading;
  ids.readIds = true;
  auto f = (*resolved)->renderFrame(outsideCamera(0.3), ids);
  ASSERT_TRUE(f.ok());
  EXPECT_FALSE(f->stats.sw.resolved) << "IDs read back: merged";
  EXPECT_TRUE(hasMerge(f.value()));
}

// Off, or a frame it does not apply to (MSAA, the overdraw count), records no micro-raster pass; an impossible size
// bound is refused with a clear error.
GPU_TEST(SwRaster, SkippedWhereItDoesNotApplyAndRefusesImpossibleBounds) {
  Scene scene = smallObjectField(2000);
  auto renderer = Renderer::create(dev, scene, {.width = 160, .height = 90});
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  auto hasSwPass = [](const FrameResult& f) {
    return std::any_of(f.stats.graph.passMs.begin(), f.stats.graph.passMs.end(),
                       [](const auto& p) { return p.first.rfind("sw ", 0) == 0; });
  };
  FrameOptions on;
  on.swRaster = SwRasterMode::On;
  auto a = (*renderer)->renderFrame(outsideCamera(0.5), on);
  ASSERT_TRUE(a.ok());
  EXPECT_TRUE(a->stats.sw.on);
  EXPECT_TRUE(hasSwPass(a.value()));
  FrameOptions off = on;
  off.swRaster = SwRasterMode::Off;
  FrameOptions overdraw = on;
  overdraw.countOverdraw = true;
  for (const FrameOptions& o : {off, overdraw}) {
    auto f = (*renderer)->renderFrame(outsideCamera(0.5), o);
    ASSERT_TRUE(f.ok());
    EXPECT_FALSE(f->stats.sw.on);
    EXPECT_FALSE(hasSwPass(f.value()));
    EXPECT_EQ(f->stats.sw.draws, 0u);
  }
  for (float px : {0.0f, -1.0f, 95.0f, float(NAN)}) {
    FrameOptions bad = on;
    bad.swRasterPixels = px;
    auto f = (*renderer)->renderFrame(outsideCamera(0.5), bad);
    ASSERT_FALSE(f.ok()) << px;
    EXPECT_EQ(f.error().code, ErrorCode::InvalidArgument);
    EXPECT_NE(f.error().message.find("micro-raster"), std::string::npos);
  }
}

// A frame in which the micro-raster took nothing (no small object) makes the next frames route everything to the
// hardware raster and record no micro-raster pass, until it probes again; the image never changes.
GPU_TEST(SwRaster, UselessMicroRasterIsSkippedAndProbedAgain) {
  FieldParams p;
  p.objects = 40;
  p.seed = 2;
  p.extent = 6.0;
  p.mesh = makeTorusKnot(48, 12);
  Scene scene = makeFieldScene(p).value();
  Camera near;  // every object large on screen
  near.position = {0.0, 0.0, 18.0};
  near.target = {0.0, 0.0, 0.0};
  near.nearPlane = 0.1;
  auto renderer = Renderer::create(dev, scene, {.width = 320, .height = 200});
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  FrameOptions on;
  on.swRaster = SwRasterMode::On;
  on.swRasterPixels = 4.0f;  // no object is that small here
  on.readIds = true;
  std::vector<bool> recorded;
  std::vector<uint32_t> firstIds;
  for (int i = 0; i < 19; ++i) {
    auto f = (*renderer)->renderFrame(near, on);
    ASSERT_TRUE(f.ok());
    EXPECT_EQ(f->stats.sw.draws, 0u);
    recorded.push_back(f->stats.sw.on);
    if (i == 0) firstIds = f->ids;
    EXPECT_EQ(f->ids, firstIds) << "frame " << i;
  }
  // Frame 0 probes, 1..16 skip, 17 probes again, 18 skips.
  for (int i = 0; i < 19; ++i) EXPECT_EQ(recorded[size_t(i)], i == 0 || i == 17) << "frame " << i;
}
