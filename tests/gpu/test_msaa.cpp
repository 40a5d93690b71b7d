// MSAA (FrameOptions::msaa): the visibility buffer's multisampled IDs + per-sample shading against the forward
// path's hardware-resolved MSAA, the per-sample path against an independent CPU count from the sample IDs, msaa 1
// against the single-sampled frame, and the refusals (unsupported counts, single-sampled-only features).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "../unit/test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/asset/texture_bake.h"
#include "gpu_test_util.h"
#include "visbuf/render/pixel_judge.h"
#include "visbuf/scene/generate.h"

namespace visbuf {
namespace {

// The largest sample count the device supports (4 on lavapipe), 0 when it has none beyond 1.
uint32_t largestMsaa(gpu::Device& dev) {
  const std::vector<uint32_t> counts = supportedMsaaSamples(dev);
  return counts.back() > 1 ? counts.back() : 0;
}

// A test that needs MSAA skips on a GPU without it (a fact about the machine), but fails on a CPU device: lavapipe,
// the CPU device of CI, supports 4 samples for every target format, so none found there is a regression of the
// query (supportedMsaaSamples), not a fact.
#define REQUIRE_MSAA(n)                                                                       \
  do {                                                                                        \
    if ((n) == 0) {                                                                           \
      if (dev.isCpu())                                                                        \
        FAIL() << dev.name() << ": lavapipe (a CPU device) supports 4x MSAA; none was found"; \
      GTEST_SKIP() << dev.name() << " supports no MSAA";                                      \
    }                                                                                         \
  } while (0)

// Many silhouettes over a textured asset: a 6 x 4 grid of copies of `file` (NormalTangentMirrorTest: base colour,
// normal and occlusion-roughness-metallic textures, mirrored UVs; Avocado from the extra corpus), each scaled to a
// unit radius with its own heading and tilt, on a ground box, with 16 point lights (the MSAA light culling path).
Scene texturedGrid(const std::filesystem::path& file) {
  EXPECT_TRUE(std::filesystem::exists(file)) << "asset missing: " << file;
  auto imported = importGltfScene(file.string(), {});
  EXPECT_TRUE(imported.ok());
  auto built = buildImportedScene(*imported);
  EXPECT_TRUE(built.ok());
  Scene s = std::move(*built);
  TextureBakeOptions to;
  to.maxTextureSize = 256;
  EXPECT_TRUE(bakeTextures(*imported, to, &s).ok());
  const std::vector<Object> asset = s.objects;
  glm::dvec4 b = objectBoundsWorld(s, asset.front());
  s.objects.clear();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int z = 0; z < 4; ++z)
    for (int x = 0; x < 6; ++x) {
      glm::dmat4 place = glm::translate(glm::dmat4(1.0), glm::dvec3(x * 1.7 - 4.25, 0.0, z * 1.7 - 2.5));
      place = glm::rotate(place, u(rng) * 6.28, glm::dvec3(0, 1, 0));
      place = glm::rotate(place, u(rng) * 1.2, glm::dvec3(1, 0, 0));
      place = glm::scale(place, glm::dvec3(1.0 / b.w));
      place = glm::translate(place, -glm::dvec3(b));
      for (const Object& o : asset) s.objects.push_back({place * o.transform, o.mesh, o.material});
    }
  s.meshes.push_back(buildMesh(makeBox(1), {.maxLods = 1}).value());
  Material ground;
  ground.baseColor = glm::vec4(0.4f, 0.45f, 0.5f, 1.0f);
  s.materials.push_back(ground);
  s.objects.push_back({glm::scale(glm::translate(glm::dmat4(1.0), glm::dvec3(0, -1.2, 0)), glm::dvec3(12, 0.2, 9)),
                       uint32_t(s.meshes.size() - 1), uint32_t(s.materials.size() - 1)});
  for (int i = 0; i < 16; ++i)
    s.pointLights.push_back({glm::dvec3(u(rng) * 10 - 5, 0.5 + u(rng), u(rng) * 7 - 3.5),
                             glm::vec3(0.5f + 0.5f * float(u(rng)), 0.7f, 0.6f), 3.0f, 3.0f});
  s.defaultCamera.position = {0.5, 4.0, 7.5};
  s.defaultCamera.target = {0.0, -0.3, 0.0};
  s.defaultCamera.nearPlane = 0.05;
  return s;
}

// Many overlapping silhouettes with interiors of many pixels: a field of randomly rotated boxes seen from outside.
Scene boxField() {
  FieldParams p;
  p.objects = 300;
  p.seed = 11;
  p.extent = 40.0;
  p.mesh = makeBox(1);
  Scene s = makeFieldScene(p).value();
  s.defaultCamera.position = {0.0, 8.0, 55.0};
  s.defaultCamera.target = {0.0, 0.0, 0.0};
  return s;
}

FrameResult render(Renderer& r, const Camera& cam, RenderPath path, uint32_t msaa, bool readIds = false) {
  FrameOptions fo;
  fo.path = path;
  fo.msaa = msaa;
  fo.lodErrorPixels = 0.0f;  // full detail: both paths draw the same triangles
  fo.readIds = readIds;
  auto f = r.renderFrame(cam, fo);
  EXPECT_TRUE(f.ok()) << (f.ok() ? "" : f.error().message);
  return f.ok() ? std::move(*f) : FrameResult{};
}

// Pixels whose samples do not all carry the same (object, triangle), from a read-back sample ID image.
size_t countDifferingPixels(const FrameResult& f, uint32_t samples) {
  size_t n = 0;
  for (size_t p = 0; p < size_t(f.width) * f.height; ++p) {
    const uint32_t* s = &f.ids[p * samples * 2];
    for (uint32_t i = 1; i < samples; ++i)
      if (s[2 * i] != s[0] || s[2 * i + 1] != s[1]) {
        ++n;
        break;
      }
  }
  return n;
}

struct Bounds {
  double psnr;            // visbuf N x vs forward N x, at least
  double maxAbs;          // largest difference, at most this or the single-sampled paths' own largest difference
  double extraDiffering;  // share of pixels > 1/255 apart, at most the single-sampled paths' share + this
  double exactMean;       // visbuf's mean difference from the exact resolve, at most
  bool visbufCloser;      // visbuf closer to the exact resolve than forward at more pixels (where shading varies
                          // across a pixel; on flat faces both are within rgba16f rounding of it)
};

// visbuf N x against forward N x (hardware resolve of per-pixel shading: the reference). MSAA must add little to
// what separates the two paths without it (visbuf 1x vs forward 1x: texture LOD from quad vs analytic
// derivatives, test_asset_bake_render.cpp), and the N x image must be much closer to the reference than the
// single-sampled visbuf image (the edges are really antialiased).
void expectMatchesForwardResolve(const Scene& scene, const char* name, uint32_t w, uint32_t h, Bounds bound) {
  gpu::Device& dev = test::testDevice();
  const uint32_t n = largestMsaa(dev);
  REQUIRE_MSAA(n);
  auto r = Renderer::create(dev, scene, {.width = w, .height = h});
  ASSERT_TRUE(r.ok()) << r.error().message;
  const Camera& cam = scene.defaultCamera;
  FrameResult vis = render(**r, cam, RenderPath::Visbuf, n, true);
  FrameResult fwd = render(**r, cam, RenderPath::Forward, n);
  FrameResult vis1 = render(**r, cam, RenderPath::Visbuf, 1);
  FrameResult fwd1 = render(**r, cam, RenderPath::Forward, 1);
  const ImageError e = compareColor(vis.color, fwd.color);
  const ImageError e1 = compareColor(vis1.color, fwd.color);
  const ImageError e11 = compareColor(vis1.color, fwd1.color);
  std::printf("%s %ux%u msaa %u: visbuf vs forward (hardware resolve) PSNR %.1f dB, max %.4f, mean %.2e, %.3f%% pixels "
              "> 1/255; per-sample pixels %u (%.2f%%). 1x vs 1x: PSNR %.1f dB, max %.4f, %.3f%% pixels; visbuf 1x vs "
              "forward %ux: PSNR %.1f dB, %.3f%% pixels\n",
              name, w, h, n, e.psnr, e.maxAbs, e.meanAbs, 100.0 * e.differingFraction, vis.stats.shade.perSamplePixels,
              100.0 * vis.stats.shade.perSamplePixels / (double(w) * h), e11.psnr, e11.maxAbs, 100.0 * e11.differingFraction,
              n, e1.psnr, 100.0 * e1.differingFraction);
  // Both resolves against the exact one (pixel_judge.h: the mean of the exact colours at the sample locations).
  auto j = judgeMsaaPixels(scene, cam, vis, fwd, n);
  ASSERT_TRUE(j.ok()) << j.error().message;
  std::printf("%s msaa %u vs exact (%zu of %zu covered pixels judged, %zu edges): visbuf max %.2e mean %.2e PSNR "
              "%.1f dB, %zu > 1/255; forward max %.2e mean %.2e PSNR %.1f dB, %zu > 1/255; of %zu differing pixels "
              "visbuf closer at %zu, forward at %zu, ties %zu\n",
              name, n, j->judged, j->covered, j->coverageMismatch, j->visbuf.maxAbs, j->visbuf.meanAbs, j->visbuf.psnr,
              j->visbuf.over8Bit, j->forward.maxAbs, j->forward.meanAbs, j->forward.psnr, j->forward.over8Bit,
              j->differing, j->visbufCloser, j->forwardCloser, j->ties);
  EXPECT_EQ(j->judged, j->covered);
  EXPECT_LE(j->visbuf.meanAbs, bound.exactMean);
  EXPECT_LE(j->visbuf.meanAbs, j->forward.meanAbs + 2e-5) << "visbuf's resolve must be as close as the hardware's";
  if (bound.visbufCloser) {
    EXPECT_GT(j->visbufCloser, j->forwardCloser);
  }
  EXPECT_GE(e.psnr, bound.psnr);
  EXPECT_LE(e.maxAbs, std::max(bound.maxAbs, e11.maxAbs));
  EXPECT_LE(e.differingFraction, e11.differingFraction + bound.extraDiffering);
  EXPECT_GE(e.psnr, e1.psnr + 6.0) << "MSAA must bring visbuf much closer to the multisampled reference than 1x";
  EXPECT_GT(vis.stats.shade.perSamplePixels, 0u);
  EXPECT_EQ(vis.stats.msaaSamples, n);
  test::saveOnFailure(fmt::format("msaa_{}", name), vis, fwd);
}

}  // namespace

// Bounds: at an edge pixel the two paths evaluate a triangle at different points. The forward path shades each
// triangle once at the pixel centre, extrapolating its attributes when the centre lies outside it (no centroid
// qualifier: its derivatives stay those of the 1x path); visbuf shades it at the mean of the sample locations it
// covers, inside it. On the Avocado grid (small, thin triangles, normal maps, 16 point lights) that puts 17 % of the
// pixels on the per-sample path and makes 3.7 % differ by more than 1/255, the largest by 0.68 (an extrapolated
// normal's specular highlight); with centroid interpolation in forward.frag the largest fell to 0.36 but its
// quad derivatives made 7.4 % differ (measured on lavapipe, not kept). Flat-faced boxes barely change across a
// pixel: 88.6 dB there. Either way visbuf 4x is 9-59 dB closer to forward 4x than visbuf 1x is.
// NormalTangentMirrorTest's normal maps are sharper than Avocado's: 14.3 % of the pixels take the per-sample path
// and the extrapolated edge normals of forward give PSNR 40.9 dB, max 0.81, 4.3 % of the pixels > 1/255 (lavapipe),
// while visbuf 1x is at 30.6 dB from forward 4x.
// Against the exact resolve (the mean of the exact colours at the 4 sample locations: what supersampling gives;
// both paths shade a triangle once per pixel, so a sample's specular highlight is missed by both), visbuf mean /
// forward mean (textured grid, Avocado, boxes, foliage): lavapipe 9.2e-4 / 2.5e-3, 5.4e-4 / 1.3e-3, 1.1e-4 /
// 1.2e-4, 9.4e-5 / 1.0e-4; H100 1.1e-3 / 2.6e-3, 5.2e-4 / 1.3e-3, 1.06e-4 / 1.03e-4, 9.4e-5 / 9.2e-5. On the
// textured grids visbuf is closer at 3-5 times as many of the pixels where the two differ; on flat faces both lie
// within rgba16f rounding of the exact resolve, and which one is closer is the device's rounding. Bounds: visbuf's
// mean at most forward's + 2e-5 and at most about twice the measured one; closer at more pixels where textured.
GPU_TEST(Msaa, VisbufMatchesForwardResolveOnTexturedAsset) {
  SKIP_WITHOUT_OIIO();
  Scene s = texturedGrid(test::assetPath("NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf"));
  ASSERT_FALSE(s.objects.empty());
  expectMatchesForwardResolve(s, "textured_grid", 320, 200, {39.0, 0.85, 0.05, 2.5e-3, true});
}

GPU_EXTRA_ASSET_TEST(Msaa, VisbufMatchesForwardResolveOnAvocadoGrid, "Avocado/glTF/Avocado.gltf") {
  SKIP_WITHOUT_OIIO();
  Scene s = texturedGrid(asset);
  ASSERT_FALSE(s.objects.empty());
  expectMatchesForwardResolve(s, "avocado_grid", 320, 200, {45.0, 0.75, 0.045, 1.2e-3, true});
}

GPU_TEST(Msaa, VisbufMatchesForwardResolveOnManySilhouettes) {
  expectMatchesForwardResolve(boxField(), "box_field", 320, 200, {80.0, 0.002, 0.0005, 2.5e-4, false});
}

// Alpha-masked, double-sided cards (the masked visibility pipelines under MSAA): the cut-out is decided per
// fragment in both paths (no sample shading), so coverage matches and only the edge evaluation points differ.
GPU_TEST(Msaa, VisbufMatchesForwardResolveOnMaskedFoliage) {
  FoliageParams p;
  p.cards = 300;
  p.extent = 8.0;
  Scene s = makeFoliageScene(p).value();
  s.defaultCamera.position = {0.0, 6.0, 18.0};
  s.defaultCamera.target = {0.0, 1.5, 0.0};
  expectMatchesForwardResolve(s, "masked_foliage", 320, 200, {80.0, 0.002, 0.0005, 2.5e-4, false});
}

// The per-sample path is taken exactly where the samples' IDs differ: the shading pass's count against a CPU count
// from the read-back sample IDs; those pixels are edges (a minority of the covered ones). Where a pixel's samples
// agree and the single-sampled frame saw the same triangle at that pixel, the colour is the 1x colour (bitwise on
// lavapipe; bounded at 1e-3).
GPU_TEST(Msaa, PerSamplePathOnlyWhereSamplesDiffer) {
  const uint32_t n = largestMsaa(dev);
  REQUIRE_MSAA(n);
  const Scene scene = boxField();
  const uint32_t w = 256, h = 160;
  auto r = Renderer::create(dev, scene, {.width = w, .height = h});
  ASSERT_TRUE(r.ok()) << r.error().message;
  FrameResult ms = render(**r, scene.defaultCamera, RenderPath::Visbuf, n, true);
  FrameResult one = render(**r, scene.defaultCamera, RenderPath::Visbuf, 1, true);
  ASSERT_EQ(ms.ids.size(), size_t(w) * h * n * 2);
  const size_t differing = countDifferingPixels(ms, n);
  size_t covered = 0, interiorCompared = 0;
  float interiorMax = 0.0f;
  for (size_t p = 0; p < size_t(w) * h; ++p) {
    const uint32_t* s = &ms.ids[p * n * 2];
    bool same = true, any = false;
    for (uint32_t i = 0; i < n; ++i) {
      same = same && s[2 * i] == s[0] && s[2 * i + 1] == s[1];
      any = any || s[2 * i] != 0;
    }
    covered += any;
    if (same && s[0] != 0 && one.ids[2 * p] == s[0] && one.ids[2 * p + 1] == s[1]) {
      ++interiorCompared;
      for (int c = 0; c < 3; ++c) interiorMax = std::max(interiorMax, std::abs(ms.color[4 * p + c] - one.color[4 * p + c]));
    }
  }
  std::printf("box field %ux%u msaa %u: %zu pixels with differing samples (CPU) vs %u per-sample pixels (GPU), %zu "
              "covered; %zu uniform pixels vs 1x: max |diff| %.2e\n",
              w, h, n, differing, ms.stats.shade.perSamplePixels, covered, interiorCompared, interiorMax);
  EXPECT_EQ(ms.stats.shade.perSamplePixels, differing);
  EXPECT_GT(differing, 0u);
  // (Edges include those between the two triangles of a box face: their IDs differ too. Measured on lavapipe:
  // 6,669 of 20,079 covered pixels.)
  EXPECT_LT(double(differing), 0.5 * double(covered)) << "only edges take the per-sample path";
  EXPECT_GT(interiorCompared, covered / 2);
  EXPECT_LE(interiorMax, 1e-3f) << "a pixel whose samples agree is shaded as without MSAA";
}

// msaa 1 is today's single-sampled frame: the same renderer after an MSAA frame, and a fresh renderer, give
// bitwise the same colour and IDs.
GPU_TEST(Msaa, OneSampleIsTheSingleSampledFrame) {
  const uint32_t n = largestMsaa(dev);
  REQUIRE_MSAA(n);
  const Scene scene = boxField();
  auto a = Renderer::create(dev, scene, {.width = 160, .height = 96});
  auto b = Renderer::create(dev, scene, {.width = 160, .height = 96});
  ASSERT_TRUE(a.ok() && b.ok());
  for (RenderPath path : {RenderPath::Visbuf, RenderPath::Forward}) {
    FrameResult fresh = render(**b, scene.defaultCamera, path, 1, path == RenderPath::Visbuf);
    render(**a, scene.defaultCamera, path, n);
    FrameResult after = render(**a, scene.defaultCamera, path, 1, path == RenderPath::Visbuf);
    EXPECT_EQ(after.color, fresh.color) << renderPathName(path);
    EXPECT_EQ(after.ids, fresh.ids) << renderPathName(path);
    EXPECT_EQ(after.stats.msaaSamples, 1u);
    EXPECT_EQ(after.stats.shade.perSamplePixels, 0u);
  }
}

// Impossible and unsupported counts, and what MSAA does not cover, are refused with errors that say why.
GPU_TEST(Msaa, UnsupportedCountsAndFeaturesAreRefused) {
  const std::vector<uint32_t> counts = supportedMsaaSamples(dev);
  ASSERT_FALSE(counts.empty());
  EXPECT_EQ(counts.front(), 1u);
  std::string list;
  for (uint32_t c : counts) list += (list.empty() ? "" : ", ") + std::to_string(c);
  std::printf("%s: supported MSAA sample counts %s\n", dev.name().c_str(), list.c_str());
  const Scene scene = boxField();
  auto r = Renderer::create(dev, scene, {.width = 64, .height = 48});
  ASSERT_TRUE(r.ok());
  auto frame = [&](FrameOptions fo) { return (*r)->renderFrame(scene.defaultCamera, fo); };
  FrameOptions fo;
  fo.msaa = 3;
  auto bad = frame(fo);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(bad.error().message.find("1, 2 or 4"), std::string::npos) << bad.error().message;
  for (uint32_t m : {2u, 4u}) {
    if (std::find(counts.begin(), counts.end(), m) != counts.end()) continue;
    fo.msaa = m;
    auto unsupported = frame(fo);
    ASSERT_FALSE(unsupported.ok());
    EXPECT_EQ(unsupported.error().code, ErrorCode::Unsupported);
    EXPECT_NE(unsupported.error().message.find("are " + list), std::string::npos) << unsupported.error().message;
  }
  const uint32_t n = largestMsaa(dev);
  if (n > 0) {
    FrameOptions g;
    g.msaa = n;
    g.path = RenderPath::GBuffer;
    FrameOptions o;
    o.msaa = n;
    o.countOverdraw = true;
    FrameOptions a;
    a.msaa = n;
    a.readAttributes = true;
    FrameOptions i;
    i.msaa = n;
    i.path = RenderPath::Forward;
    i.readIds = true;
    for (const FrameOptions& x : {g, o, a, i}) {
      auto refused = frame(x);
      ASSERT_FALSE(refused.ok());
      EXPECT_NE(refused.error().message.find("single-sampled only"), std::string::npos) << refused.error().message;
    }
    Scene blend = scene;
    Material glass;
    glass.alphaMode = AlphaMode::Blend;
    glass.baseColor.a = 0.5f;
    blend.materials.push_back(glass);
    blend.objects.front().material = uint32_t(blend.materials.size() - 1);
    auto rb = Renderer::create(dev, blend, {.width = 64, .height = 48});
    ASSERT_TRUE(rb.ok());
    FrameOptions t;
    t.msaa = n;
    auto refused = (*rb)->renderFrame(blend.defaultCamera, t);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("BLEND"), std::string::npos) << refused.error().message;
    t.msaa = 1;
    EXPECT_TRUE((*rb)->renderFrame(blend.defaultCamera, t).ok());
  }
}

}  // namespace visbuf
