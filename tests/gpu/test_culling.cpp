// Culling is conservative: against a double-precision CPU reference over random cameras, and pixel for
// pixel (IDs) against no culling at all along camera paths.
#include <algorithm>
#include <random>
#include <set>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "gpu_test_util.h"
#include "visbuf/render/frame_math.h"
#include "visbuf/scene/generate.h"

using namespace visbuf;

namespace {

Scene fieldScene(uint32_t objects, bool lowPoly) {
  FieldParams p;
  p.objects = objects;
  p.seed = 5;
  if (lowPoly) p.mesh = makeTorusKnot(48, 12);  // 1,152 triangles: keeps "cull none" frames affordable
  return makeFieldScene(p).value();
}

Scene cityScene(uint32_t objects) {
  CityParams p;
  p.objects = objects;
  p.seed = 3;
  return makeCityScene(p).value();
}

Camera randomCamera(std::mt19937& rng, const Scene& scene) {
  // Cameras inside and around the scene's bounds, looking anywhere, various fields of view.
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const Object& o : scene.objects) {
    glm::dvec3 t(o.transform[3]);
    lo = glm::min(lo, t);
    hi = glm::max(hi, t);
  }
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Camera c;
  glm::dvec3 ext = hi - lo;
  c.position = lo - 0.2 * ext + glm::dvec3(u(rng), u(rng), u(rng)) * ext * 1.4;
  glm::dvec3 dir = glm::normalize(glm::dvec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) + glm::dvec3(1e-3));
  c.target = c.position + dir * 10.0;
  c.up = std::abs(dir.y) > 0.99 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  c.fovY = glm::radians(20.0 + 90.0 * u(rng));
  c.nearPlane = 0.05 + u(rng);
  // A third of them orthographic (a box with a far plane), a third perspective with a finite far plane and an
  // authored aspect ratio, the rest infinite perspective with the viewport's aspect.
  const double kind = u(rng), far = c.nearPlane + 5.0 + u(rng) * glm::length(ext);
  if (kind < 1.0 / 3.0) {
    c.projection = Projection::Orthographic;
    c.xmag = 1.0 + u(rng) * 0.3 * glm::length(ext);
    c.ymag = c.xmag * (0.3 + u(rng));
    c.nearPlane = u(rng) < 0.3 ? 0.0 : c.nearPlane;
    c.farPlane = far;
  } else if (kind < 2.0 / 3.0) {
    c.farPlane = far;
    c.aspectRatio = 0.5 + 2.0 * u(rng);
  }
  return c;
}

void checkConservative(const Scene& scene, const char* label) {
  gpu::Device& dev = test::testDevice();
  auto renderer = Renderer::create(dev, scene, {.width = 320, .height = 200});
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  std::mt19937 rng(1234);
  FrameOptions fo;
  fo.cull = CullMode::Frustum;
  fo.lodErrorPixels = 0.0f;
  fo.readColor = false;
  fo.readDraws = true;
  fo.clusters = false;  // the objects' test (an object it keeps may lose every cluster: test_clusters.cpp)
  size_t totalKept = 0, totalExtra = 0;
  double worstExtra = 0.0;
  for (int i = 0; i < 100; ++i) {
    Camera cam = randomCamera(rng, scene);
    auto frame = (*renderer)->renderFrame(cam, fo);
    ASSERT_TRUE(frame.ok()) << frame.error().message;
    std::vector<char> gpuKept(scene.objects.size(), 0);
    for (uint32_t id : frame->drawnObjects) {
      ASSERT_LT(id, scene.objects.size());
      ASSERT_EQ(gpuKept[id], 0) << "object drawn twice";
      gpuKept[id] = 1;
    }
    FrameMath fm = computeFrameMath(cam, 320, 200);
    for (size_t o = 0; o < scene.objects.size(); ++o) {
      glm::dvec4 s = objectBoundsWorld(scene, scene.objects[o]);
      double dist = sphereFrustumDistance(fm, cam, glm::dvec3(s), s.w);  // <= 0: the reference keeps it
      if (dist <= 0.0) {
        ++totalKept;
        ASSERT_TRUE(gpuKept[o]) << label << ": camera " << i << " dropped object " << o << " that the double "
                                << "reference keeps (distance " << dist << ")";
      } else if (gpuKept[o]) {
        // Allowed only within the stated tolerance of a plane: 2e-5 x (|centre - camera|_1 + r) + 1e-5.
        glm::dvec3 c = glm::dvec3(s) - cam.position;
        double tol = 2e-5 * (std::abs(c.x) + std::abs(c.y) + std::abs(c.z) + s.w) + 1e-5;
        ++totalExtra;
        worstExtra = std::max(worstExtra, dist / tol);
        EXPECT_LE(dist, tol) << label << ": camera " << i << " kept object " << o << " " << dist << " outside";
      }
    }
  }
  std::printf("%s: 100 cameras, %zu object-frames kept by the reference, %zu extra kept by the GPU "
              "(worst at %.3f of the tolerance)\n", label, totalKept, totalExtra, worstExtra);
  EXPECT_GT(totalKept, 0u);
}

// A camera path: orbit, fly-through, a cut, grazing views.
std::vector<Camera> cameraPath(const Scene& scene, int frames, bool city) {
  std::vector<Camera> path;
  for (int i = 0; i < frames; ++i) {
    double t = double(i) / frames;
    Camera c = scene.defaultCamera;
    if (city) {
      c.position = scene.defaultCamera.position + glm::dvec3(0.0, 0.5 * std::sin(t * 6.28), -t * 150.0);
      double yaw = std::sin(t * 12.0) * 1.2;
      c.target = c.position + glm::dvec3(std::sin(yaw), -0.05, -std::cos(yaw));
      if (i == frames / 2) c.position += glm::dvec3(30.0, 20.0, 10.0);  // a cut
    } else {
      double r = 420.0 * (1.0 - 0.9 * t);  // from outside into the field
      c.position = {r * std::sin(t * 5.0), 80.0 * std::sin(t * 3.0), r * std::cos(t * 5.0)};
      c.target = c.position + glm::dvec3(-std::sin(t * 5.0 + 0.3), -0.1, -std::cos(t * 5.0 + 0.3));
      c.nearPlane = 0.1;
    }
    path.push_back(c);
  }
  return path;
}

struct PathEvent {
  int frame;
  uint32_t width = 0, height = 0;  // resize when non-zero
  bool clearHistory = false;       // camera cut: forget last frame's visible set
};

// Renders every camera of the path with `mode` and with no culling at all (LOD off) and requires
// identical decoded ID images. Occlusion mode keeps its history across frames, so the path exercises
// the two-phase scheme with stale history, cuts and resizes.
// msaa > 1: every sample's ID is compared (the sub-pixel test and the pyramid must keep any covered sample).
// `cameras` (when not empty) replaces the path (label: what the log calls it).
void checkIdEquality(const Scene& scene, bool city, int frames, uint32_t w, uint32_t h,
                     CullMode mode = CullMode::Frustum, std::vector<PathEvent> events = {}, uint32_t msaa = 1,
                     const std::vector<Camera>& cameras = {}, const char* label = nullptr) {
  gpu::Device& dev = test::testDevice();
  auto renderer = Renderer::create(dev, scene, {.width = w, .height = h});
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  FrameOptions on, off;
  on.lodErrorPixels = off.lodErrorPixels = 0.0f;  // LOD off: both draw the same triangles
  on.readColor = off.readColor = false;
  on.readIds = off.readIds = true;
  on.cull = mode;
  off.cull = CullMode::None;
  on.msaa = off.msaa = msaa;
  // Clusters on (the default): drawing the culled frame's near objects as their surviving clusters must change no
  // pixel either. The micro-raster would take small clusters there while the unculled frame draws those objects
  // whole with the hardware raster, and the two rasters may break an edge tie differently (its own bounds:
  // SwRaster.MatchesHardwareRaster; with culling: SwRaster.IdImageUnchangedByCulling): hardware raster only.
  on.swRaster = off.swRaster = SwRasterMode::Off;
  size_t covered = 0, culledTotal = 0, occludedTotal = 0, drawnTotal = 0, visibleTotal = 0;
  int index = 0;
  for (const Camera& cam : cameras.empty() ? cameraPath(scene, frames, city) : cameras) {
    for (const PathEvent& e : events) {
      if (e.frame != index) continue;
      if (e.width) {
        ASSERT_TRUE((*renderer)->resize(e.width, e.height).ok());
      }
      if (e.clearHistory) (*renderer)->clearHistory();
    }
    auto a = (*renderer)->renderFrame(cam, on);
    auto b = (*renderer)->renderFrame(cam, off);
    ASSERT_TRUE(a.ok() && b.ok());
    culledTotal += a->stats.cull.frustumCulled + a->stats.cull.occlusionCulled + a->stats.cull.subpixelCulled;
    occludedTotal += a->stats.cull.occlusionCulled;
    drawnTotal += a->stats.cull.drawsRendered;
    std::set<uint32_t> visible;
    for (size_t p = 0; p < a->ids.size(); p += 2)
      if (a->ids[p]) visible.insert(a->ids[p]);
    visibleTotal += visible.size();
    size_t mismatches = 0;
    for (size_t p = 0; p < a->ids.size(); p += 2) {
      if (a->ids[p] != b->ids[p] || a->ids[p + 1] != b->ids[p + 1]) ++mismatches;
      covered += a->ids[p] != 0;
    }
    ASSERT_EQ(mismatches, 0u) << "frame " << index << ": culling changed " << mismatches << " pixels";
    ++index;
  }
  if (msaa > 1) std::printf("msaa %u, every sample: ", msaa);
  std::printf("%s %ux%u %s: %d frames identical to no culling (%zu covered pixels, %zu objects culled, %zu "
              "occluded; drawn %zu vs %zu visible in the image = %.2fx)\n",
              label ? label : city ? "city" : "field", w, h, cullModeName(mode), index, covered, culledTotal, occludedTotal,
              drawnTotal, visibleTotal, visibleTotal ? double(drawnTotal) / double(visibleTotal) : 0.0);
  EXPECT_GT(covered, 0u);
  EXPECT_GT(culledTotal, 0u) << "the path must exercise culling";
}

}  // namespace

GPU_TEST(Culling, ConservativeVsDoubleReferenceField) { checkConservative(fieldScene(4000, true), "field"); }
GPU_TEST(Culling, ConservativeVsDoubleReferenceCity) { checkConservative(cityScene(4000), "city"); }

GPU_TEST(Culling, IdImageUnchangedByCullingField) { checkIdEquality(fieldScene(1500, true), false, 50, 317, 229); }
GPU_TEST(Culling, IdImageUnchangedByCullingCity) { checkIdEquality(cityScene(1200), true, 50, 317, 229); }

// Occlusion culling never hides anything: 100-frame paths with a camera cut, a cleared history and a
// resize in the middle, at a non-power-of-two size.
GPU_TEST(Occlusion, IdImageUnchangedByOcclusionCullingCity) {
  checkIdEquality(cityScene(1200), true, 100, 317, 229, CullMode::Occlusion,
                  {{40, 0, 0, true}, {60, 160, 90, false}, {61, 0, 0, false}, {80, 319, 181, true}});
}
// Orthographic views (cull_tests.glsl: box-shaped frustum with a far plane, screen rectangles without the divide, a
// linear depth for the pyramid test, the cone test along the view direction): LOD off, the ID image with occlusion
// culling equals the one without. Street level along the city's avenues (buildings hide each other) and from above
// at a slant, a near plane of 0 and one cutting through buildings, a far plane cutting the city; non-square windows.
GPU_TEST(Occlusion, IdImageUnchangedByOcclusionCullingOrthographic) {
  Scene city = cityScene(1200);
  std::vector<Camera> views;
  const glm::dvec3 eye = city.defaultCamera.position;
  for (int i = 0; i < 10; ++i) {
    Camera c;
    c.projection = Projection::Orthographic;
    const double t = i / 10.0;
    c.position = eye + glm::dvec3(10.0 * std::sin(t * 6.0), 1.0 + 60.0 * t * t, -40.0 * t);
    const double yaw = std::sin(t * 9.0) * 0.8;
    c.target = c.position + glm::dvec3(std::sin(yaw), -0.05 - 0.8 * t, -std::cos(yaw));
    c.xmag = 20.0 + 30.0 * t;
    c.ymag = 12.0 + 10.0 * t;
    c.nearPlane = i % 3 == 0 ? 0.0 : 5.0;
    c.farPlane = i % 4 == 1 ? 120.0 : 2000.0;
    views.push_back(c);
  }
  checkIdEquality(city, true, int(views.size()), 317, 229, CullMode::Occlusion, {{5, 0, 0, true}}, 1, views,
                  "city orthographic");
  checkIdEquality(city, true, int(views.size()), 317, 229, CullMode::Frustum, {}, 1, views, "city orthographic");
}

GPU_TEST(Occlusion, IdImageUnchangedByOcclusionCullingField) {
  checkIdEquality(fieldScene(1500, true), false, 100, 317, 229, CullMode::Occlusion,
                  {{50, 211, 97, false}, {75, 0, 0, true}});
}
// With MSAA: the pyramid is the farthest depth over each pixel's samples and the sub-pixel test keeps bounds that
// can cover a sample but no pixel centre; every sample's ID must still equal the one with no culling. (The largest
// supported count; lavapipe: 4.)
GPU_TEST(Occlusion, IdImageUnchangedByOcclusionCullingMsaa) {
  const uint32_t msaa = supportedMsaaSamples(dev).back();
  if (msaa == 1) {  // a fact about a GPU; lavapipe, the CPU device of CI, supports 4 samples
    ASSERT_FALSE(dev.isCpu()) << dev.name()
                              << ": lavapipe (a CPU device) supports 4x MSAA; supportedMsaaSamples found none";
    GTEST_SKIP() << "no MSAA on this device";
  }
  checkIdEquality(cityScene(1200), true, 12, 211, 157, CullMode::Occlusion, {{5, 0, 0, true}, {8, 160, 90, false}},
                  msaa);
  checkIdEquality(fieldScene(1500, true), false, 16, 317, 229, CullMode::Occlusion, {{8, 0, 0, true}}, msaa);
}
// The depth pyramid at sizes with odd, non-power-of-two and degenerate levels.
GPU_TEST(Occlusion, IdImageUnchangedAtAwkwardResolutions) {
  Scene city = cityScene(1200);
  for (auto [w, h] : {std::pair{1366u, 768u}, {1280u, 720u}, {1920u, 1080u}, {1u, 1u}, {3u, 5u}, {5u, 3u}, {33u, 17u}})
    checkIdEquality(city, true, 3, w, h, CullMode::Occlusion);
}

// The depth pyramid against an independent CPU reduction: every level-k texel (x, y) must equal the
// minimum (reverse-Z farthest) of level 0 over [x 2^k, (x+1) 2^k) x [y 2^k, (y+1) 2^k) clipped to the
// image, at sizes with odd, non-power-of-two and degenerate levels.
GPU_TEST(Occlusion, DepthPyramidMatchesCpuReduction) {
  Scene city = cityScene(600);
  for (auto [w, h] : {std::pair{1366u, 768u}, {1280u, 720u}, {1920u, 1080u}, {1u, 1u}, {3u, 5u}, {37u, 11u}}) {
    auto renderer = Renderer::create(dev, city, {.width = w, .height = h});
    ASSERT_TRUE(renderer.ok());
    FrameOptions fo;
    fo.readColor = false;
    fo.readPyramid = true;
    fo.skipUselessPyramid = false;  // build it every frame, even where it hides nothing
    (*renderer)->renderFrame(city.defaultCamera, fo).value();  // history settles: early depth non-empty
    auto f = (*renderer)->renderFrame(city.defaultCamera, fo);
    ASSERT_TRUE(f.ok());
    ASSERT_FALSE(f->pyramid.empty());
    const auto& l0 = f->pyramid[0];
    ASSERT_EQ(l0.width, w);
    ASSERT_EQ(l0.height, h);
    EXPECT_EQ(f->pyramid.back().width, 1u);
    EXPECT_EQ(f->pyramid.back().height, 1u);
    size_t nonZero = 0;
    for (float d : l0.depth) nonZero += d > 0.0f;
    if (w * h > 100) {
      EXPECT_GT(nonZero, 0u) << "the early phase must have drawn something";
    }
    for (size_t k = 1; k < f->pyramid.size(); ++k) {
      const auto& lk = f->pyramid[k];
      ASSERT_EQ(lk.width, (w + (1u << k) - 1) >> k);
      ASSERT_EQ(lk.height, (h + (1u << k) - 1) >> k);
      for (uint32_t y = 0; y < lk.height; ++y)
        for (uint32_t x = 0; x < lk.width; ++x) {
          float expect = 1.0f;
          for (uint32_t py = y << k; py < std::min(h, (y + 1) << k); ++py)
            for (uint32_t px = x << k; px < std::min(w, (x + 1) << k); ++px)
              expect = std::min(expect, l0.depth[size_t(py) * w + px]);
          ASSERT_EQ(lk.depth[size_t(y) * lk.width + x], expect) << w << "x" << h << " level " << k << " texel " << x << "," << y;
        }
    }
  }
}

// --freeze-culling: the frozen frame draws exactly the draw lists of the frame it froze.
GPU_TEST(Occlusion, FrozenCullingRedrawsTheFrozenDrawLists) {
  Scene city = cityScene(1200);
  auto renderer = Renderer::create(dev, city, {.width = 320, .height = 180});
  ASSERT_TRUE(renderer.ok());
  FrameOptions fo;
  fo.readColor = false;
  fo.readDraws = true;
  Result<FrameResult> culled = makeError(ErrorCode::InvalidArgument, "");
  for (int i = 0; i < 3; ++i) culled = (*renderer)->renderFrame(city.defaultCamera, fo);
  ASSERT_TRUE(culled.ok());
  Camera elsewhere = city.defaultCamera;
  elsewhere.position += glm::dvec3(0.0, 80.0, 60.0);
  fo.freezeCulling = true;
  auto frozen = (*renderer)->renderFrame(elsewhere, fo);
  ASSERT_TRUE(frozen.ok());
  EXPECT_TRUE(frozen->stats.cull.cullingFrozen);
  EXPECT_EQ(frozen->stats.pyramid.levels, 0u) << "a frozen frame builds no pyramid";
  auto sorted = [](std::vector<uint32_t> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_EQ(sorted(frozen->drawnObjects), sorted(culled->drawnObjects));
  fo.freezeCulling = false;
  auto live = (*renderer)->renderFrame(elsewhere, fo);
  ASSERT_TRUE(live.ok());
  EXPECT_NE(sorted(live->drawnObjects), sorted(culled->drawnObjects)) << "the moved camera sees other objects";
}

// Skipping what the scene does not need: a pyramid that hid nothing is not built on the next frames,
// and the image stays identical to no culling while it is skipped.
// ID-only frames, LOD off: the default occlusion culling, and no culling at all (the reference).
static std::pair<FrameOptions, FrameOptions> idFramesWithAndWithoutCulling() {
  FrameOptions fo, none;
  fo.readColor = none.readColor = false;
  fo.readIds = none.readIds = true;
  fo.lodErrorPixels = none.lodErrorPixels = 0.0f;
  none.cull = CullMode::None;
  return {fo, none};
}

// The early phase runs over the late phase's list of the visible set (one thread per listed object): with a steady
// camera it draws exactly what the previous frame found visible and the late phase draws nothing new; a cleared
// history empties it without changing a pixel.
GPU_TEST(Occlusion, EarlyPhaseDrawsLastFramesVisibleList) {
  Scene city = cityScene(1200);
  auto renderer = Renderer::create(dev, city, {.width = 320, .height = 180});
  ASSERT_TRUE(renderer.ok());
  auto [fo, none] = idFramesWithAndWithoutCulling();
  fo.clusters = false;  // one draw per visible object (clusters: several)
  auto reference = (*renderer)->renderFrame(city.defaultCamera, none);
  ASSERT_TRUE(reference.ok());
  auto visibleAtEnd = [](const FrameStats& s) {
    return s.cull.objectsTested - s.cull.frustumCulled - s.cull.occlusionCulled - s.cull.subpixelCulled;
  };
  uint32_t lastVisible = 0;
  for (int i = 0; i < 6; ++i) {
    if (i == 4) (*renderer)->clearHistory();
    auto f = (*renderer)->renderFrame(city.defaultCamera, fo);
    ASSERT_TRUE(f.ok());
    ASSERT_EQ(f->ids, reference->ids) << "frame " << i;
    const FrameStats& s = f->stats;
    if (i == 0 || i == 4) {
      EXPECT_EQ(s.cull.drawsEarly, 0u) << "frame " << i << ": no history, nothing listed";
    } else {
      EXPECT_EQ(s.cull.drawsEarly, lastVisible) << "frame " << i << ": last frame's visible set, drawn early";
    }
    if (i == 2 || i == 3) {  // steady: the early set is the visible set, the late phase adds nothing
      EXPECT_EQ(s.cull.drawsLate, 0u) << "frame " << i;
      EXPECT_EQ(s.cull.drawsEarly, visibleAtEnd(s)) << "frame " << i;
    }
    lastVisible = visibleAtEnd(s);
  }
  EXPECT_GT(lastVisible, 0u);
  EXPECT_LT(lastVisible, city.objects.size()) << "the camera sees only part of the city";
}

// The late phase tests what the coarse pyramid level (2x2 texels over the object's rectangle) kept again three
// levels finer, in a dispatch of its own over those objects: it must occlude some of them in an occluded city,
// never more than it tested, and leave every frame's IDs those of the unculled frame.
GPU_TEST(Occlusion, FinerLevelOccludesWhatTheCoarseLevelKept) {
  Scene city = cityScene(3000);
  auto renderer = Renderer::create(dev, city, {.width = 640, .height = 360});
  ASSERT_TRUE(renderer.ok());
  const auto [fo, none] = idFramesWithAndWithoutCulling();
  auto reference = (*renderer)->renderFrame(city.defaultCamera, none);
  ASSERT_TRUE(reference.ok());
  for (int i = 0; i < 3; ++i) {
    auto f = (*renderer)->renderFrame(city.defaultCamera, fo);
    ASSERT_TRUE(f.ok());
    ASSERT_EQ(f->ids, reference->ids) << "frame " << i;
    const FrameStats& s = f->stats;
    EXPECT_LE(s.cull.refineOccluded, s.cull.refineTested) << "frame " << i;
    EXPECT_LE(s.cull.refineOccluded, s.cull.occlusionCulled) << "frame " << i;
    if (i > 0) {  // with a depth pyramid of the early phase
      EXPECT_GT(s.cull.refineTested, 0u) << "frame " << i;
      EXPECT_GT(s.cull.refineOccluded, 0u) << "frame " << i;
    }
    std::printf("frame %d: %u occluded, %u tested again finer, %u of them occluded\n", i, s.cull.occlusionCulled,
                s.cull.refineTested, s.cull.refineOccluded);
  }
}

GPU_TEST(Occlusion, UselessPyramidIsSkippedAndProbedAgain) {
  Scene field = fieldScene(40, true);  // 40 thin knots in a 600-unit cube: nothing occludes anything
  auto renderer = Renderer::create(dev, field, {.width = 160, .height = 90});
  ASSERT_TRUE(renderer.ok());
  const auto [fo, none] = idFramesWithAndWithoutCulling();
  uint32_t built = 0, skipped = 0;
  for (int i = 0; i < 40; ++i) {
    auto f = (*renderer)->renderFrame(field.defaultCamera, fo);
    ASSERT_TRUE(f.ok());
    if (f->stats.pyramid.levels) {
      ++built;
      EXPECT_EQ(f->stats.cull.occlusionCulled, 0u);
    }
    skipped += f->stats.pyramid.skipped;
    auto ref = (*renderer)->renderFrame(field.defaultCamera, none);
    ASSERT_EQ(f->ids, ref->ids) << "frame " << i;
  }
  EXPECT_EQ(built + skipped, 40u);
  EXPECT_GE(skipped, 30u);
  EXPECT_GE(built, 2u) << "the pyramid is probed again";
}

// The spatial object order (orderObjectsSpatially) renumbers the objects and changes nothing else: along a path
// from outside into the field, with occlusion culling, LOD and the micro-raster on (the defaults), every pixel's
// colour is the same and its ID is the same object (renumbered) and triangle.
GPU_TEST(Culling, SpatialObjectOrderChangesNoPixel) {
  const Scene built = fieldScene(3000, true);
  Scene ordered = built;
  const std::vector<uint32_t> order = orderObjectsSpatially(ordered);
  ASSERT_NE(ordered.objects[0].transform, built.objects[0].transform) << "the order must renumber something";
  auto a = Renderer::create(dev, built, {.width = 256, .height = 192});
  auto b = Renderer::create(dev, ordered, {.width = 256, .height = 192});
  ASSERT_TRUE(a.ok() && b.ok());
  FrameOptions fo;
  fo.readIds = true;
  size_t covered = 0;
  int index = 0;
  for (const Camera& cam : cameraPath(built, 12, false)) {
    auto fa = (*a)->renderFrame(cam, fo);
    auto fb = (*b)->renderFrame(cam, fo);
    ASSERT_TRUE(fa.ok() && fb.ok());
    ASSERT_EQ(fa->color, fb->color) << "frame " << index;
    for (size_t p = 0; p < fa->ids.size(); p += 2) {
      const uint32_t renumbered = fb->ids[p] ? order.at(fb->ids[p] - 1) + 1 : 0u;
      ASSERT_EQ(fa->ids[p], renumbered) << "frame " << index << " pixel " << p / 2;
      ASSERT_EQ(fa->ids[p + 1], fb->ids[p + 1]) << "frame " << index << " pixel " << p / 2;
      covered += fa->ids[p] != 0;
    }
    ++index;
  }
  EXPECT_GT(covered, 10000u);
}
