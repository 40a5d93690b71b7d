// Cluster culling (config.h CULL_CLUSTERS): drawing the hardware raster's objects as their surviving clusters must
// not change a pixel. Every test renders the same frames with clusters on and off and compares the IDs (object,
// triangle of its LOD level) pixel for pixel.
#include <algorithm>
#include <cstdio>
#include <memory>

#include <glm/gtc/matrix_transform.hpp>

#include "gpu_test_util.h"
#include "visbuf/scene/generate.h"

using namespace visbuf;

namespace {

// A dense field of 28,800-triangle torus knots around the origin (1,500 in 40^3), every seventh one mirrored (the flipped draw
// list: its clusters' cones are tested in object space, where a mirror keeps the front faces).
Scene denseField(uint32_t objects) {
  FieldParams p;
  p.objects = objects;
  p.seed = 17;
  p.extent = 20.0;
  Scene s = makeFieldScene(p).value();
  for (size_t i = 0; i < s.objects.size(); i += 7) s.objects[i].transform = glm::scale(s.objects[i].transform, glm::dvec3(-1, 1, 1));
  return s;
}

// From inside the field, turning and moving: near objects fill much of the view, partly outside it, and objects
// coming out from behind others are drawn in the late phase with their hidden clusters tested against the pyramid.
Camera insideCamera(int frame) {
  Camera c;
  const double t = frame * 0.04;
  c.position = {6.0 * std::sin(t), 2.0 * std::sin(0.7 * t), 6.0 * std::cos(t) - 10.0};
  c.target = c.position + glm::dvec3(std::sin(2.0 * t + 0.5), 0.2 * std::cos(t), std::cos(2.0 * t + 0.5));
  c.fovY = glm::radians(70.0);
  c.nearPlane = 0.5;
  return c;
}

struct Totals {
  size_t frames = 0, covered = 0, otherTriangle = 0, otherObject = 0;
  CullStats::Clusters clusters;
  size_t swDrawsOn = 0, swDrawsOff = 0;
};

// Renders `frames` frames of the path with clusters on and off (same options otherwise; a camera cut and a cleared
// history at `cut`) and counts the pixels whose IDs differ.
Totals compareClusters(Renderer& r, FrameOptions options, int frames, int cut) {
  FrameOptions on = options, off = options;
  on.readIds = off.readIds = true;
  on.readColor = off.readColor = false;
  on.clusters = true;
  off.clusters = false;
  Totals t;
  for (int i = 0; i < frames; ++i) {
    if (i == cut) r.clearHistory();
    const Camera cam = insideCamera(i == cut ? i + 20 : i);
    auto a = r.renderFrame(cam, on);
    auto b = r.renderFrame(cam, off);
    EXPECT_TRUE(a.ok() && b.ok());
    if (!a.ok() || !b.ok()) return t;
    EXPECT_EQ(b->stats.cull.clusters.objects, 0u);
    EXPECT_EQ(a->stats.cull.drawOverflow, 0u);
    const auto& c = a->stats.cull.clusters;
    t.clusters.objects += c.objects;
    t.clusters.tested += c.tested;
    t.clusters.frustumCulled += c.frustumCulled;
    t.clusters.backfacing += c.backfacing;
    t.clusters.occluded += c.occluded;
    t.clusters.draws += c.draws;
    t.clusters.deferred += c.deferred;
    t.clusters.recovered += c.recovered;
    EXPECT_EQ(b->stats.cull.clusters.deferred, 0u);
    t.swDrawsOn += a->stats.sw.draws;
    t.swDrawsOff += b->stats.sw.draws;
    for (size_t p = 0; p < a->ids.size(); p += 2) {
      t.covered += b->ids[p] != 0;
      if (a->ids[p] != b->ids[p])
        ++t.otherObject;
      else if (a->ids[p + 1] != b->ids[p + 1])
        ++t.otherTriangle;
    }
    ++t.frames;
  }
  std::printf("%zu frames: %zu objects as clusters, %zu clusters tested, %zu outside the frustum, %zu back-facing, "
              "%zu occluded; %zu draws (micro-raster draws %zu vs %zu without clusters); %zu deferred by the early "
              "phase, %zu of them drawn late; %zu of %zu covered pixels another triangle, %zu another object\n",
              t.frames, size_t(t.clusters.objects), size_t(t.clusters.tested), size_t(t.clusters.frustumCulled),
              size_t(t.clusters.backfacing), size_t(t.clusters.occluded), size_t(t.clusters.draws), t.swDrawsOn,
              t.swDrawsOff, size_t(t.clusters.deferred), size_t(t.clusters.recovered), t.otherTriangle, t.covered, t.otherObject);
  return t;
}

// Both tests: the dense field at 320x200 (the renderer keeps a reference to its scene); validation messages counted
// from its creation to its destruction.
class Clusters : public test::GpuTest {
 protected:
  void SetUp() override {
    test::GpuTest::SetUp();
    auto r = Renderer::create(dev, scene, {.width = 320, .height = 200});
    ASSERT_TRUE(r.ok()) << r.error().message;
    renderer = std::move(r.value());
  }
  void TearDown() override {
    renderer.reset();
    test::GpuTest::TearDown();
  }
  Scene scene = denseField(1500);
  std::unique_ptr<Renderer> renderer;
};

}  // namespace

// With the hardware raster alone, clusters are the same triangles drawn by other commands: every pixel must hold the
// same object and triangle, with LOD on and off, occlusion culling with its history across frames and a cut.
TEST_F(Clusters, IdImageUnchangedByClusterCulling) {
  FrameOptions fo;
  fo.cull = CullMode::Occlusion;
  fo.swRaster = SwRasterMode::Off;
  for (float lodPixels : {1.0f, 0.0f}) {
    fo.lodErrorPixels = lodPixels;
    const Totals t = compareClusters(*renderer, fo, lodPixels > 0.0f ? 16 : 6, lodPixels > 0.0f ? 8 : 3);
    EXPECT_EQ(t.otherObject + t.otherTriangle, 0u) << "LOD " << lodPixels << " px: clusters changed pixels";
    EXPECT_GT(t.covered, t.frames * 320 * 200 / 4);
    EXPECT_GT(t.clusters.objects, 0u);
    EXPECT_GT(t.clusters.frustumCulled, 0u);
    // (the field's knots are thin tubes: their clusters' normals spread wide, more so at coarse levels)
    const uint32_t inFrustum = t.clusters.tested - t.clusters.frustumCulled;
    EXPECT_GT(t.clusters.backfacing, lodPixels > 0.0f ? 0u : inFrustum / 20) << "the path must exercise the cone test";
    EXPECT_GT(t.clusters.occluded, 0u) << "the path must exercise the late phase's pyramid test";
    // Last frame's pyramid hides clusters that the turning camera shows now: the late retest must draw them.
    EXPECT_GT(t.clusters.recovered, 0u) << "the path must exercise the early phase's deferral and the retest";
    EXPECT_LT(t.clusters.recovered, t.clusters.deferred);
  }
  // Frustum culling alone (one phase, no pyramid).
  fo.cull = CullMode::Frustum;
  fo.lodErrorPixels = 1.0f;
  const Totals t = compareClusters(*renderer, fo, 4, -1);
  EXPECT_EQ(t.otherObject + t.otherTriangle, 0u);
  EXPECT_GT(t.clusters.backfacing, 0u);
  EXPECT_EQ(t.clusters.deferred, 0u) << "no pyramid, no deferral";
}

// Small clusters go to the micro-raster: against the frames without clusters, pixels may change only where the two
// rasters break an edge tie differently (the bounds of SwRaster.MatchesHardwareRaster: 0.05 % of the pixels another
// triangle, 0.01 % another object).
TEST_F(Clusters, MicroRasterClustersMatchHardwareRaster) {
  FrameOptions fo;
  fo.cull = CullMode::Occlusion;
  fo.swRaster = SwRasterMode::On;
  const Totals t = compareClusters(*renderer, fo, 12, 6);
  const size_t pixels = t.frames * 320 * 200;
  EXPECT_GT(t.swDrawsOn, t.swDrawsOff) << "the micro-raster must take clusters";
  EXPECT_GT(t.clusters.recovered, 0u) << "deferred clusters must reach the micro-raster in the late phase too";
  EXPECT_LE(t.otherTriangle, pixels / 2000);
  EXPECT_LE(t.otherObject, pixels / 10000);
}
