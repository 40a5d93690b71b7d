// Alpha-masked, double-sided and blended geometry (issue 5, items 2 and 5): the masked visibility raster's
// cut-outs against the forward reference (exact coverage) and a double-precision ray cast, culling on == off,
// the transparency pass against a CPU composite (sort order), and AlphaBlendModeTest in both paths.
//
// Alpha comes from maskAlpha() (shaders/alpha_mask.glsl): material base colour alpha x vertex colour alpha.
// The foliage cards carry their alpha pattern in COLOR_0 (a gradient across each card), so these tests hold
// unchanged once maskAlpha() also samples the base colour texture (their materials have none).
#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "../unit/test_assets.h"
#include "gpu_test_util.h"
#include "visbuf/render/brdf_reference.h"
#include "visbuf/render/frame_math.h"
#include "visbuf/scene/generate.h"

using namespace visbuf;

namespace {

// Shading bounds of tests/gpu/test_shading.cpp (interpolation and rgba16f rounding only).
constexpr double kMaxAbs = 2e-3;
constexpr double kMeanAbs = 5e-5;
constexpr double kMinPsnr = 80.0;

// A unit card in the XY plane ([-0.5, 0.5]^2, normal +Z, counter-clockwise seen from +Z) whose COLOR_0 alpha
// runs from 0 at x = -0.5 to 1 at x = +0.5: with cutoff 0.5 exactly the half x >= 0 stays (alpha = x + 0.5,
// perspective-correct interpolation keeps it linear in object space).
MeshSource makeCard() {
  MeshSource m;
  m.name = "card";
  m.positions = {{-0.5f, -0.5f, 0.0f}, {0.5f, -0.5f, 0.0f}, {0.5f, 0.5f, 0.0f}, {-0.5f, 0.5f, 0.0f}};
  m.normals.assign(4, glm::vec3(0.0f, 0.0f, 1.0f));
  m.uvs = {{0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}, {0.0f, 0.0f}};
  m.colors = {0x00ffffffu, 0xffffffffu, 0xffffffffu, 0x00ffffffu};  // RGBA8, alpha in the high byte
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

Material material(AlphaMode mode, bool doubleSided, glm::vec4 color, float cutoff = 0.5f) {
  Material m;
  m.name = "m";
  m.baseColor = color;
  m.alphaMode = mode;
  m.alphaCutoff = cutoff;
  m.doubleSided = doubleSided;
  m.metallic = 0.0f;
  return m;
}

// Foliage-like: many overlapping cards at random orientations (so many are seen from the back), a third of
// them mirrored (negative determinant). Materials: 0 MASK double-sided (most cards), 1 MASK single-sided,
// 2 opaque single-sided, 3 opaque double-sided: every draw list is used.
Scene makeFoliage(uint32_t cards, uint32_t seed) {
  Scene s;
  s.name = "foliage";
  s.meshes.push_back(buildMesh(makeCard()).value());
  s.materials = {material(AlphaMode::Mask, true, {0.3f, 0.8f, 0.3f, 1.0f}),
                 material(AlphaMode::Mask, false, {0.8f, 0.7f, 0.2f, 1.0f}),
                 material(AlphaMode::Opaque, false, {0.6f, 0.4f, 0.3f, 1.0f}),
                 material(AlphaMode::Opaque, true, {0.3f, 0.4f, 0.8f, 1.0f})};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (uint32_t i = 0; i < cards; ++i) {
    glm::dvec3 axis(u(rng), u(rng), u(rng));
    if (glm::length(axis) < 1e-3) axis = {0, 1, 0};
    glm::dmat4 t = glm::translate(glm::dmat4(1.0), glm::dvec3(5.0 * u(rng), 3.0 * u(rng), 5.0 * u(rng)));
    t = glm::rotate(t, 3.14159 * u(rng), glm::normalize(axis));
    const double scale = 2.0 + u(rng);
    t = glm::scale(t, glm::dvec3(i % 3 == 2 ? -scale : scale, scale, scale));
    const uint32_t m = i % 10 < 6 ? 0u : i % 10 - 6u;
    s.objects.push_back({t, 0, m});
  }
  s.defaultCamera.position = {1.0, 2.0, 16.0};
  s.defaultCamera.target = {0.0, 0.0, 0.0};
  return s;
}

// VISBUF_ALPHA_IMAGES=DIR: also write the pictures of docs/alpha.md there.
void writeDocImage(const std::string& name, const FrameResult& f) {
  const char* dir = std::getenv("VISBUF_ALPHA_IMAGES");
  if (!dir) return;
  Status s = writeColorImage(std::string(dir) + "/" + name + ".png", f.width, f.height, f.color);
  EXPECT_TRUE(s.ok()) << s.error().message;
}

Result<FrameResult> render(Renderer& r, const Camera& cam, RenderPath path, CullMode cull) {
  FrameOptions fo;
  fo.path = path;
  fo.cull = cull;
  fo.lodErrorPixels = 0.0f;
  fo.readIds = true;
  return r.renderFrame(cam, fo);
}

// Coverage and colour of visbuf against the forward reference: (object, triangle) per pixel identical on lavapipe
// (a GPU may break depth ties between the two pipelines differently at <= 0.1% of the pixels, as in
// test_shading.cpp), colour within the shading bounds where the coverage agrees.
void expectMatchesForward(const FrameResult& vis, const FrameResult& fwd, const std::string& name) {
  ASSERT_EQ(vis.ids.size(), fwd.ids.size());
  size_t mismatch = 0, covered = 0;
  std::vector<float> a = vis.color, b = fwd.color;
  for (size_t p = 0; p < vis.ids.size() / 2; ++p) {
    covered += fwd.ids[2 * p] != 0;
    if (vis.ids[2 * p] != fwd.ids[2 * p] || vis.ids[2 * p + 1] != fwd.ids[2 * p + 1]) {
      ++mismatch;
      for (int c = 0; c < 4; ++c) a[p * 4 + c] = b[p * 4 + c] = 0.0f;
    }
  }
  const test::ImageError e = test::compareColor(a, b);
  std::printf("%s: %zu covered pixels, %zu differ in coverage; colour max %.5f mean %.6f PSNR %.1f dB\n",
              name.c_str(), covered, mismatch, e.maxAbs, e.meanAbs, e.psnr);
  EXPECT_GT(covered, 0u);
  if (test::testDevice().isCpu()) {
    EXPECT_EQ(mismatch, 0u) << name << ": cut-outs must match the forward reference exactly";
  }
  EXPECT_LE(double(mismatch), 1e-3 * double(covered));
  EXPECT_LE(e.maxAbs, kMaxAbs) << name;
  EXPECT_LE(e.meanAbs, kMeanAbs) << name;
  EXPECT_GE(e.psnr, kMinPsnr) << name;
  test::saveOnFailure(name, vis, fwd);
}

// Whether a card shows its front face to a point: its +Z normal through the inverse transpose (glTF: a mirrored
// object's front faces are clockwise, and its front is where this normal points).
bool cardFaces(const Object& o, glm::dvec3 eye) {
  const glm::dmat3 m(o.transform);
  const glm::dvec3 n = glm::transpose(glm::inverse(m)) * glm::dvec3(0, 0, 1);
  return glm::dot(n, eye - glm::dvec3(o.transform[3])) > 0.0;
}

}  // namespace

GPU_TEST(AlphaMask, FoliageCoverageMatchesForwardExactly) {
  Scene scene = makeFoliage(160, 7);
  auto r = Renderer::create(dev, scene, {.width = 320, .height = 240});
  ASSERT_TRUE(r.ok()) << r.error().message;
  const Camera& cam = scene.defaultCamera;
  auto fwd = render(**r, cam, RenderPath::Forward, CullMode::Frustum);
  ASSERT_TRUE(fwd.ok());
  for (CullMode cull : {CullMode::None, CullMode::Frustum, CullMode::Occlusion}) {
    (*r)->clearHistory();
    // Occlusion: the second frame has a history (early phase) and a pyramid (late phase).
    for (int frame = 0; frame < (cull == CullMode::Occlusion ? 2 : 1); ++frame) {
      auto vis = render(**r, cam, RenderPath::Visbuf, cull);
      ASSERT_TRUE(vis.ok());
      EXPECT_EQ(vis->stats.cull.drawOverflow, 0u);
      expectMatchesForward(*vis, *fwd, std::string("foliage_") + cullModeName(cull) + std::to_string(frame));
      if (cull == CullMode::Occlusion && frame == 1) writeDocImage("foliage_visbuf", *vis);
    }
  }
  writeDocImage("foliage_forward", *fwd);
  // What the scene shows: back faces of double-sided cards, never the back face of a single-sided card (the
  // cut-outs themselves: CutOutAreaMatchesRayCast).
  std::vector<size_t> pixelsOf(scene.objects.size(), 0);
  for (size_t p = 0; p < fwd->ids.size() / 2; ++p)
    if (fwd->ids[2 * p]) ++pixelsOf[fwd->ids[2 * p] - 1];
  size_t backDoubleSided = 0;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    const bool doubleSided = scene.materials[o.material].doubleSided;
    if (!cardFaces(o, cam.position)) {
      if (doubleSided) backDoubleSided += pixelsOf[i];
      if (!doubleSided) {
        EXPECT_EQ(pixelsOf[i], 0u) << "single-sided card " << i << " seen from the back is drawn";
      }
    }
  }
  EXPECT_GT(backDoubleSided, 1000u) << "double-sided cards seen from the back must be drawn";
}

// One card, seen from the front and from the back: covered pixels are exactly those whose centre's ray hits
// the kept half (object x >= 0) of the card in a double-precision ray cast, except within 1e-3 card units of
// an edge or of the cut line (float rounding of the raster and of the interpolated alpha).
GPU_TEST(AlphaMask, CutOutAreaMatchesRayCast) {
  Scene scene;
  scene.meshes.push_back(buildMesh(makeCard()).value());
  scene.materials = {material(AlphaMode::Mask, true, {0.5f, 0.9f, 0.5f, 1.0f})};
  const double size = 4.0;
  const glm::dmat4 t = glm::rotate(glm::scale(glm::dmat4(1.0), glm::dvec3(size)), 0.3, glm::dvec3(0, 1, 0));
  scene.objects.push_back({t, 0, 0});
  const uint32_t w = 256, h = 192;
  auto r = Renderer::create(dev, scene, {.width = w, .height = h});
  ASSERT_TRUE(r.ok()) << r.error().message;
  for (double side : {1.0, -1.0}) {
    Camera cam;
    cam.position = {0.7, 0.4, 9.0 * side};
    cam.target = {0.0, 0.0, 0.0};
    const FrameMath math = computeFrameMath(cam, w, h);
    const glm::dmat4 inv = glm::inverse(math.viewProj);
    const glm::dmat4 toObject = glm::inverse(t);
    for (RenderPath path : {RenderPath::Visbuf, RenderPath::Forward}) {
      auto f = render(**r, cam, path, CullMode::Occlusion);
      ASSERT_TRUE(f.ok());
      size_t covered = 0, expected = 0, wrong = 0, whole = 0;
      for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
          // Pixel centre -> camera-relative ray -> object space -> the card's plane z = 0.
          const glm::dvec2 ndc((x + 0.5) / w * 2.0 - 1.0, (y + 0.5) / h * 2.0 - 1.0);
          glm::dvec4 farPoint = inv * glm::dvec4(ndc, 0.5, 1.0);
          const glm::dvec3 dir = glm::dvec3(farPoint) / farPoint.w;
          const glm::dvec3 o = glm::dvec3(toObject * glm::dvec4(cam.position, 1.0));
          const glm::dvec3 d = glm::dvec3(toObject * glm::dvec4(dir, 0.0));
          const double s = -o.z / d.z;
          const glm::dvec3 hit = o + s * d;
          const bool inCard = s > 0 && std::abs(hit.x) <= 0.5 && std::abs(hit.y) <= 0.5;
          const bool kept = inCard && hit.x >= 0.0;
          const double margin = std::min({std::abs(std::abs(hit.x) - 0.5), std::abs(std::abs(hit.y) - 0.5),
                                          std::abs(hit.x)});
          const bool isCovered = f->ids[2 * (size_t(y) * w + x)] != 0;
          covered += isCovered;
          expected += kept;
          whole += inCard;
          if (isCovered != kept && margin > 1e-3) ++wrong;
        }
      std::printf("cut-out %s, %s: %zu covered, ray cast: %zu kept of %zu on the card, %zu wrong\n",
                  side > 0 ? "front" : "back", renderPathName(path), covered, expected, whole, wrong);
      EXPECT_EQ(wrong, 0u);
      EXPECT_GT(expected, 2000u);
      EXPECT_NEAR(double(covered), double(expected), 0.01 * double(expected));
      EXPECT_LT(double(expected), 0.6 * double(whole)) << "about half of the card is cut out";
      EXPECT_GT(double(expected), 0.4 * double(whole));
    }
  }
}

// Each draw list has its own capacity (--draw-capacity applies per list) and overflow is counted exactly: with
// culling off every object is appended to its list, so the CPU knows what each list keeps and drops.
GPU_TEST(AlphaMask, OverflowCountedPerDrawList) {
  Scene scene = makeFoliage(160, 7);
  const uint32_t cap = 20;
  auto r = Renderer::create(dev, scene, {.width = 96, .height = 64, .drawCapacity = cap});
  ASSERT_TRUE(r.ok()) << r.error().message;
  std::array<uint32_t, DRAW_LISTS> perList{};
  for (const Object& o : scene.objects) {
    const Material& m = scene.materials[o.material];
    const bool mirrored = glm::determinant(glm::dmat3(o.transform)) < 0.0;
    const uint32_t base = m.alphaMode == AlphaMode::Mask ? DRAW_LIST_MASKED : DRAW_LIST_OPAQUE;
    ++perList[m.doubleSided ? base + 2 : mirrored ? base + 1 : base];
  }
  uint32_t kept = 0, dropped = 0, lists = 0;
  for (uint32_t n : perList) {
    kept += std::min(n, cap);
    dropped += n > cap ? n - cap : 0;
    lists += n > 0;
  }
  EXPECT_EQ(lists, uint32_t(DRAW_LISTS)) << "the foliage scene uses every draw list";
  EXPECT_GT(dropped, 0u);
  FrameOptions fo;
  fo.cull = CullMode::None;
  fo.readDraws = true;
  auto f = (*r)->renderFrame(scene.defaultCamera, fo);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->stats.cull.drawsAppended, uint32_t(scene.objects.size()));
  EXPECT_EQ(f->stats.cull.drawsRendered, kept);
  EXPECT_EQ(f->stats.cull.drawOverflow, dropped);
  EXPECT_EQ(f->drawnObjects.size(), size_t(kept));
  std::vector<uint32_t> drawn = f->drawnObjects;
  std::sort(drawn.begin(), drawn.end());
  EXPECT_EQ(std::adjacent_find(drawn.begin(), drawn.end()), drawn.end()) << "no object drawn twice";
}

GPU_TEST(AlphaMask, OpaqueSceneRecordsNothingExtra) {
  Scene scene = makeFieldScene({.objects = 50, .extent = 20.0}).value();
  auto r = Renderer::create(dev, scene, {.width = 64, .height = 64});
  ASSERT_TRUE(r.ok());
  for (RenderPath path : {RenderPath::Visbuf, RenderPath::Forward}) {
    FrameOptions fo;
    fo.path = path;
    fo.cull = CullMode::Frustum;
    fo.swRaster = SwRasterMode::Off;  // (its passes are the micro-raster's tests' subject: test_sw_raster.cpp)
    auto f = (*r)->renderFrame(scene.defaultCamera, fo);
    ASSERT_TRUE(f.ok());
    EXPECT_EQ(f->stats.transparent.draws, 0u);
    std::vector<std::string> names;
    for (const auto& p : f->stats.graph.passMs) names.push_back(p.first);
    const std::vector<std::string> expected =
        path == RenderPath::Visbuf ? std::vector<std::string>{"cull", "visibility", "shade"}
                                   : std::vector<std::string>{"forward"};
    EXPECT_EQ(names, expected);
  }
}

namespace {

Mesh plainCard() {
  MeshSource m = makeCard();
  m.colors.assign(4, 0xffffffffu);
  return buildMesh(m).value();
}

glm::dmat4 placeCard(glm::dvec3 centre, double size) {
  return glm::scale(glm::translate(glm::dmat4(1.0), centre), glm::dvec3(size));
}

// The lit colour of a card facing +z at `world` (camera at `camera`), by the double-precision BRDF reference.
glm::dvec3 litFacingZ(const Scene& s, glm::dvec3 baseColor, glm::dvec3 world, glm::dvec3 camera) {
  SurfaceReference r;
  r.position = world - camera;
  r.normal = {0.0, 0.0, 1.0};
  r.baseColor = baseColor;
  r.metallic = s.materials[0].metallic;
  r.roughness = s.materials[0].roughness;
  return shadeReference(r, s, camera);
}

glm::dvec3 over(glm::dvec4 src, glm::dvec3 lit, glm::dvec3 dst) { return src.a * lit + (1.0 - src.a) * dst; }

}  // namespace

// Two overlapping transparent cards (the near one first in the scene, so an unsorted pass would get it wrong)
// in front of an opaque backdrop, partly behind an opaque occluder: each probed pixel against the composite
// computed on the CPU back to front (glTF BLEND: colour x alpha + (1 - alpha) x behind), in both paths.
// Tolerance 4e-3: rgba16f rounding of up to three blend steps (half ulp at 1.0 = 4.9e-4 each) and the lighting
// in float. The reverse order differs from the expected result by more than 0.05 at the overlap.
GPU_TEST(Transparency, BackToFrontMatchesCpuComposite) {
  Scene s;
  s.meshes.push_back(plainCard());
  const glm::dvec4 nearColor(1.0, 0.1, 0.1, 0.5), farColor(0.1, 0.2, 1.0, 0.6), backdrop(0.5, 0.5, 0.5, 1.0),
      occluder(0.2, 0.8, 0.2, 1.0);
  s.materials = {material(AlphaMode::Blend, false, glm::vec4(nearColor)),
                 material(AlphaMode::Blend, false, glm::vec4(farColor)),
                 material(AlphaMode::Opaque, false, glm::vec4(backdrop)),
                 material(AlphaMode::Opaque, false, glm::vec4(occluder))};
  s.objects = {{placeCard({-0.6, 0.0, 0.0}, 2.0), 0, 0},
               {placeCard({0.6, 0.0, -2.0}, 2.0), 0, 1},
               {placeCard({0.0, 0.0, -4.0}, 12.0), 0, 2},
               {placeCard({0.0, -0.4, 1.0}, 0.6), 0, 3}};
  Camera cam;
  cam.position = {0.0, 0.0, 6.0};
  cam.target = {0.0, 0.0, 0.0};
  s.defaultCamera = cam;
  const uint32_t w = 320, h = 240;
  auto r = Renderer::create(dev, s, {.width = w, .height = h});
  ASSERT_TRUE(r.ok()) << r.error().message;

  // Lit colours at each probe (the BRDF depends on the view direction, so per probe point).
  auto lit = [&](glm::dvec4 c, glm::dvec3 world) { return litFacingZ(s, glm::dvec3(c), world, cam.position); };
  auto probeAt = [&](const char* what, glm::dvec3 world, glm::dvec3 onFar, glm::dvec3 onBack, int layers) {
    const glm::dvec3 back = lit(backdrop, onBack);
    glm::dvec3 e = back;
    if (layers & 2) e = over(farColor, lit(farColor, onFar), e);
    if (layers & 1) e = over(nearColor, lit(nearColor, world), e);
    return std::make_pair(what, std::make_pair(world, e));
  };
  // A probe's ray (from the camera through `world` on the near card's plane z = 0) meets the far card (z = -2)
  // and the backdrop (z = -4) at these points.
  auto along = [&](glm::dvec3 world, double z) {
    const glm::dvec3 d = world - cam.position;
    return cam.position + d * ((z - cam.position.z) / d.z);
  };
  struct Probe {
    const char* what;
    glm::dvec3 world;
    glm::dvec3 expected;
  };
  std::vector<Probe> probes;
  for (auto [what, pt, layers] : {std::tuple{"overlap", glm::dvec3(0.05, 0.4, 0.0), 3},
                                 std::tuple{"far only", along(glm::dvec3(1.2, 0.0, -2.0), 0.0), 2},
                                 std::tuple{"near only", glm::dvec3(-1.2, 0.0, 0.0), 1},
                                 std::tuple{"backdrop", along(glm::dvec3(-4.0, 3.0, -4.0), 0.0), 0}}) {
    auto pr = probeAt(what, pt, along(pt, -2.0), along(pt, -4.0), layers);
    probes.push_back({pr.first, layers == 0 ? along(pt, -4.0) : layers == 2 ? along(pt, -2.0) : pt, pr.second.second});
  }
  probes.push_back({"occluded", {0.0, -0.4, 1.0}, lit(occluder, {0.0, -0.4, 1.0})});
  const glm::dvec3 wOverlap(0.05, 0.4, 0.0);
  const glm::dvec3 nearLit = lit(nearColor, wOverlap), farLit = lit(farColor, along(wOverlap, -2.0)),
                   back = lit(backdrop, along(wOverlap, -4.0));
  const glm::dvec3 wrongOrder = over(farColor, farLit, over(nearColor, nearLit, back));
  EXPECT_GT(glm::length(wrongOrder - probes[0].expected), 0.05) << "the probe must tell the orders apart";
  const FrameMath math = computeFrameMath(cam, w, h);
  for (RenderPath path : {RenderPath::Visbuf, RenderPath::Forward}) {
    FrameOptions fo;
    fo.path = path;
    auto f = (*r)->renderFrame(cam, fo);
    ASSERT_TRUE(f.ok());
    writeDocImage(std::string("transparency_") + renderPathName(path), *f);
    EXPECT_EQ(f->stats.transparent.draws, 2u);
    bool recorded = false;
    for (const auto& p : f->stats.graph.passMs) recorded |= p.first == "transparent";
    EXPECT_TRUE(recorded);
    for (const Probe& p : probes) {
      const glm::dvec4 clip = math.viewProj * glm::dvec4(p.world - cam.position, 1.0);
      const glm::dvec2 px = (glm::dvec2(clip) / clip.w * 0.5 + 0.5) * glm::dvec2(w, h);
      const size_t i = size_t(px.y) * w + size_t(px.x);
      const glm::dvec3 got(f->color[4 * i], f->color[4 * i + 1], f->color[4 * i + 2]);
      std::printf("%s %s: got (%.4f %.4f %.4f), expected (%.4f %.4f %.4f)\n", renderPathName(path), p.what, got.x,
                  got.y, got.z, p.expected.x, p.expected.y, p.expected.z);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(got[c], p.expected[c], 4e-3) << renderPathName(path) << " " << p.what << " channel " << c;
      }
    }
  }
}

namespace {

std::filesystem::path assetPath(const char* relative) { return test::assetPath(relative); }

int materialNamed(const Scene& s, const std::string& name) {
  for (size_t i = 0; i < s.materials.size(); ++i)
    if (s.materials[i].name == name) return int(i);
  return -1;
}

}  // namespace

// AlphaBlendModeTest: visbuf vs forward within the shading bounds, as the file is and with its BLEND and MASK
// materials given a base colour alpha of 0.5 (their alpha is in textures, which maskAlpha() does not sample yet):
// MatBlend's pixels then lie between the object rendered opaque and what is behind it, and differ from the opaque
// render; MatCutoff75 (cutoff 0.75 > 0.5) is cut out entirely, MatCutoff25 (0.25) is not.
GPU_TEST(Transparency, AlphaBlendModeTestBlendsAndCutsOut) {
  const std::filesystem::path file = assetPath("AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf");
  REQUIRE_ASSET(file);
  Result<ImportedScene> imported = importGltfScene(file.string());
  ASSERT_TRUE(imported) << imported.error().message;
  Result<Scene> loaded = buildImportedScene(*imported);
  ASSERT_TRUE(loaded) << loaded.error().message;
  const Scene& original = *loaded;
  const int blend = materialNamed(original, "MatBlend"), cut75 = materialNamed(original, "MatCutoff75"),
            cut25 = materialNamed(original, "MatCutoff25");
  ASSERT_TRUE(blend >= 0 && cut75 >= 0 && cut25 >= 0);
  ASSERT_EQ(original.materials[size_t(blend)].alphaMode, AlphaMode::Blend);
  ASSERT_EQ(original.materials[size_t(cut75)].alphaMode, AlphaMode::Mask);

  Scene halfAlpha = original;
  for (int m : {blend, cut75, cut25}) halfAlpha.materials[size_t(m)].baseColor.a = 0.5f;
  Scene opaque = halfAlpha;  // the blended objects drawn opaque (their own colour and coverage)
  opaque.materials[size_t(blend)].alphaMode = AlphaMode::Opaque;
  Scene without = halfAlpha;  // what is behind them
  std::erase_if(without.objects, [&](const Object& o) { return int(o.material) == blend; });
  ASSERT_LT(without.objects.size(), original.objects.size());

  const uint32_t w = 384, h = 384;
  const Camera cam = original.defaultCamera;
  auto renderBoth = [&](const Scene& scene, const std::string& name) -> std::pair<FrameResult, FrameResult> {
    auto r = Renderer::create(dev, scene, {.width = w, .height = h});
    EXPECT_TRUE(r.ok());
    auto vis = render(**r, cam, RenderPath::Visbuf, CullMode::Occlusion);
    auto fwd = render(**r, cam, RenderPath::Forward, CullMode::Frustum);
    EXPECT_TRUE(vis.ok() && fwd.ok());
    expectMatchesForward(*vis, *fwd, name);
    return {std::move(*vis), std::move(*fwd)};
  };
  auto pixelsWithMaterial = [&](const Scene& scene, const FrameResult& f, int m) {
    size_t n = 0;
    for (size_t p = 0; p < f.ids.size() / 2; ++p) n += f.ids[2 * p] && int(scene.objects[f.ids[2 * p] - 1].material) == m;
    return n;
  };
  auto [origVis, origFwd] = renderBoth(original, "alphablend_original");
  auto [halfVis, halfFwd] = renderBoth(halfAlpha, "alphablend_half");
  auto [opaqueVis, opaqueFwd] = renderBoth(opaque, "alphablend_opaque");
  auto [withoutVis, withoutFwd] = renderBoth(without, "alphablend_without");
  writeDocImage("AlphaBlendModeTest_half_alpha_visbuf", halfVis);
  writeDocImage("AlphaBlendModeTest_half_alpha_forward", halfFwd);

  EXPECT_GT(pixelsWithMaterial(original, origFwd, cut75), 500u);
  EXPECT_EQ(pixelsWithMaterial(halfAlpha, halfVis, cut75), 0u) << "alpha 0.5 < cutoff 0.75: cut out";
  EXPECT_EQ(pixelsWithMaterial(halfAlpha, halfFwd, cut75), 0u);
  EXPECT_GT(pixelsWithMaterial(halfAlpha, halfVis, cut25), 500u) << "alpha 0.5 >= cutoff 0.25: kept";

  // With alpha a <= 0.5 (0.5 x any texture alpha): got - object = (1 - a) (behind - object), (1 - a) >= 0.5.
  for (const FrameResult* f : {&halfVis, &halfFwd}) {
    size_t blendPixels = 0, contrasting = 0, blended = 0, outside = 0;
    for (size_t p = 0; p < f->ids.size() / 2; ++p) {
      if (!opaqueFwd.ids[2 * p] || int(opaque.objects[opaqueFwd.ids[2 * p] - 1].material) != blend) continue;
      ++blendPixels;
      int strongest = 0;
      for (int c = 0; c < 3; ++c) {
        const float got = f->color[4 * p + c], obj = opaqueFwd.color[4 * p + c], behind = withoutFwd.color[4 * p + c];
        outside += got < std::min(obj, behind) - 3e-3f || got > std::max(obj, behind) + 3e-3f;
        if (std::abs(behind - obj) > std::abs(withoutFwd.color[4 * p + strongest] - opaqueFwd.color[4 * p + strongest]))
          strongest = c;
      }
      const float obj = opaqueFwd.color[4 * p + strongest], behind = withoutFwd.color[4 * p + strongest];
      if (std::abs(behind - obj) < 0.05f) continue;  // object and background alike here: blending shows little
      ++contrasting;
      blended += std::abs(f->color[4 * p + strongest] - obj) >= 0.45f * std::abs(behind - obj);
    }
    std::printf("MatBlend: %zu pixels, %zu where it contrasts with what is behind, %zu of those blended at alpha "
                "<= 0.5, %zu channels outside [object, behind]\n", blendPixels, contrasting, blended, outside);
    EXPECT_GT(blendPixels, 500u);
    EXPECT_GT(contrasting, 100u);
    EXPECT_EQ(blended, contrasting);
    EXPECT_EQ(outside, 0u);
  }
}

// A scene of BLEND objects only: no draw list has objects (nothing rasterised into the IDs), and the
// transparency pass alone draws, the same in both paths.
GPU_TEST(Transparency, OnlyBlendedObjects) {
  Scene s;
  s.meshes.push_back(plainCard());
  s.materials = {material(AlphaMode::Blend, true, {0.9f, 0.5f, 0.1f, 0.4f})};
  s.objects = {{placeCard({0.0, 0.0, 0.0}, 2.0), 0, 0}, {placeCard({0.5, 0.3, -1.0}, 2.0), 0, 0}};
  s.defaultCamera.position = {0.0, 0.0, 5.0};
  auto r = Renderer::create(dev, s, {.width = 64, .height = 48});
  ASSERT_TRUE(r.ok()) << r.error().message;
  auto vis = render(**r, s.defaultCamera, RenderPath::Visbuf, CullMode::Occlusion);
  auto fwd = render(**r, s.defaultCamera, RenderPath::Forward, CullMode::Frustum);
  ASSERT_TRUE(vis.ok() && fwd.ok());
  EXPECT_EQ(vis->stats.cull.drawsRendered, 0u);
  EXPECT_EQ(vis->stats.transparent.draws, 2u);
  EXPECT_EQ(fwd->stats.transparent.draws, 2u);
  EXPECT_TRUE(std::all_of(vis->ids.begin(), vis->ids.end(), [](uint32_t v) { return v == 0; }));
  const test::ImageError e = test::compareColor(vis->color, fwd->color);
  EXPECT_LE(e.maxAbs, kMaxAbs);
  size_t tinted = 0;  // pixels the cards changed from the background
  for (size_t p = 0; p < vis->color.size(); p += 4) tinted += std::abs(vis->color[p] - 0.10f) > 0.05f;
  EXPECT_GT(tinted, 200u);
}
