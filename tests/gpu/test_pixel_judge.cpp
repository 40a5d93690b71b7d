// The per-pixel judge (engine/render/pixel_judge.h) on frames of a known scene: the visbuf path's colour is the
// double-precision exact colour up to float arithmetic and rgba16f rounding, every covered pixel of a static scene
// is judged (textured ones too), a pixel a path gets wrong is found and blamed on that path, and what the judge cannot
// judge is refused with a reason.
#include "gpu_test_util.h"
#include "../unit/test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/asset/texture_bake.h"
#include "visbuf/render/pixel_judge.h"
#include "visbuf/scene/generate.h"

using namespace visbuf;

namespace {

struct Frames {
  FrameResult visbuf, forward;
};

Frames renderBoth(const Scene& scene, const Camera& cam, uint32_t w, uint32_t h) {
  auto renderer = Renderer::create(test::testDevice(), scene, {.width = w, .height = h});
  EXPECT_TRUE(renderer.ok());
  auto [vis, fwd] = test::renderBothPaths(**renderer, cam);
  EXPECT_TRUE(vis.ok() && fwd.ok());
  return {std::move(vis.value()), std::move(fwd.value())};
}

// One knot filling a good part of a non-square frame.
Scene knotScene(Camera& cam) {
  FieldParams p;
  p.objects = 1;
  Scene scene = makeFieldScene(p).value();
  const glm::dvec3 c(scene.objects[0].transform[3]);
  cam.position = c + glm::dvec3(0.0, 0.6, 4.0);
  cam.target = c;
  cam.nearPlane = 0.01;
  return scene;
}

}  // namespace

// Bounds: rgba16f keeps 11 significant bits, so a correct colour near 1 is up to half an ulp (2.4e-4) from the
// exact one; float interpolation and lighting add a few float ulps. Measured on lavapipe: see the summary printed.
GPU_TEST(PixelJudge, VisbufPathIsExactOnAnUntexturedKnot) {
  Camera cam;
  const Scene scene = knotScene(cam);
  const Frames f = renderBoth(scene, cam, 160, 120);
  auto j = judgePixels(scene, cam, f.visbuf, f.forward);
  ASSERT_TRUE(j.ok()) << j.error().message;
  std::printf("judge knot: %zu covered, %zu judged; visbuf max %.2e mean %.2e PSNR %.1f dB; forward max %.2e mean "
              "%.2e PSNR %.1f dB; %zu differ: visbuf closer %zu, forward closer %zu, ties %zu\n",
              j->covered, j->judged, j->visbuf.maxAbs, j->visbuf.meanAbs, j->visbuf.psnr, j->forward.maxAbs,
              j->forward.meanAbs, j->forward.psnr, j->differing, j->visbufCloser, j->forwardCloser, j->ties);
  EXPECT_GT(j->covered, size_t(160 * 120 / 10)) << "the knot must fill part of the frame";
  EXPECT_EQ(j->judged, j->covered) << "an untextured static scene is judged everywhere";
  EXPECT_EQ(j->coverageMismatch, 0u);
  EXPECT_LE(j->visbuf.maxAbs, 1e-3);
  EXPECT_GE(j->visbuf.psnr, 80.0);
  ASSERT_EQ(j->heatMap.size(), f.visbuf.color.size());
}

// A pixel one path gets wrong: the forward frame's pixel is replaced by the background (what a raster that missed
// the triangle would show). The ray hits the triangle the visbuf path claims, so the exact colour is its colour
// and the visbuf path is the closer one; replacing a colour alone (same IDs) blames the changed path too.
GPU_TEST(PixelJudge, BlamesThePathThatIsOff) {
  Camera cam;
  const Scene scene = knotScene(cam);
  Frames f = renderBoth(scene, cam, 96, 72);
  std::vector<size_t> covered;  // (two from the middle of the list: inside the knot's silhouette)
  for (size_t p = 0; p < size_t(96) * 72; ++p)
    if (f.visbuf.ids[2 * p] != 0) covered.push_back(p);
  ASSERT_GT(covered.size(), 100u);
  const size_t missed = covered[covered.size() / 2], recoloured = covered[covered.size() / 2 + 1];
  f.forward.ids[2 * missed] = f.forward.ids[2 * missed + 1] = 0;
  for (int c = 0; c < 3; ++c) f.forward.color[4 * missed + size_t(c)] = kBackgroundColor[c];
  f.visbuf.color[4 * recoloured] += 0.25f;
  auto j = judgePixels(scene, cam, f.visbuf, f.forward);
  ASSERT_TRUE(j.ok()) << j.error().message;
  EXPECT_EQ(j->coverageMismatch, 1u);
  EXPECT_GE(j->visbufCloser, 1u) << "the missed pixel";
  EXPECT_GE(j->forwardCloser, 1u) << "the recoloured pixel";
  EXPECT_GE(j->visbuf.maxAbs, 0.24);
  EXPECT_GE(j->forward.over8Bit, 1u);
  EXPECT_GT(j->heatMap[4 * recoloured], j->heatMap[4 * recoloured + 1]) << "red: the visbuf path is off";
}

GPU_TEST(PixelJudge, RefusesWhatItCannotJudge) {
  Camera cam;
  Scene scene = knotScene(cam);
  Frames f = renderBoth(scene, cam, 32, 24);
  FrameResult small = f.forward;
  small.width = 16;
  EXPECT_EQ(judgePixels(scene, cam, f.visbuf, small).error().code, ErrorCode::InvalidArgument);
  FrameResult noIds = f.forward;
  noIds.ids.clear();
  EXPECT_EQ(judgePixels(scene, cam, f.visbuf, noIds).error().code, ErrorCode::InvalidArgument);
  FrameResult badId = f.forward;
  badId.ids[0] = 7;  // object 6 of a one-object scene
  EXPECT_EQ(judgePixels(scene, cam, f.visbuf, badId).error().code, ErrorCode::InvalidArgument);
  FrameResult coarse = f.forward;  // drew LOD 1 without saying which objects
  coarse.stats.cull.lodHistogram = {0u, 1u};
  coarse.drawnObjects.clear();
  EXPECT_EQ(judgePixels(scene, cam, f.visbuf, coarse).error().code, ErrorCode::InvalidArgument);
  scene.materials[0].alphaMode = AlphaMode::Blend;
  auto blend = judgePixels(scene, cam, f.visbuf, f.forward);
  ASSERT_FALSE(blend.ok());
  EXPECT_NE(blend.error().message.find("BLEND"), std::string::npos) << blend.error().message;
}

namespace {

void printJudgement(const char* name, const PixelJudgement& j) {
  std::printf("judge %s: %zu of %zu covered pixels judged; visbuf max %.2e (%.1e beyond rgba16f rounding) mean %.2e "
              "PSNR %.1f dB, %zu > 1/255; forward max %.2e (%.1e beyond) mean %.2e PSNR %.1f dB, %zu > 1/255; %zu "
              "differ: visbuf closer %zu, forward closer %zu, ties %zu\n",
              name, j.judged, j.covered, j.visbuf.maxAbs, j.visbuf.maxBeyondRounding, j.visbuf.meanAbs, j.visbuf.psnr,
              j.visbuf.over8Bit, j.forward.maxAbs, j.forward.maxBeyondRounding, j.forward.meanAbs, j.forward.psnr,
              j.forward.over8Bit, j.differing, j.visbufCloser, j.forwardCloser, j.ties);
}

}  // namespace

// Textured materials (generated: sRGB checkers and stripes, linear noise, trilinear with full mip chains) on the
// city at street level, where the ground's mip level changes along every row: the exact colour samples the same
// textures with the exact uv derivatives. The visbuf path's analytic derivatives agree with them. Measured on
// lavapipe (2026-11): visbuf max 1.25e-3, 70.0 dB; forward (quad derivatives) max 5.2e-2, 54.6 dB. Bounds: about
// twice the visbuf path's largest error, 5 dB under its PSNR; the forward path is not bounded here (Materials.*).
GPU_TEST(PixelJudge, JudgesTexturedMaterials) {
  Scene scene = makeCityScene({.objects = 600, .seed = 2}).value();
  ASSERT_TRUE(applyGeneratedMaterials(scene, 8, 3).ok());
  Camera cam = scene.defaultCamera;
  cam.position.y = 1.5;
  cam.target = cam.position + glm::dvec3(0.2, -0.15, -1.0);
  const Frames f = renderBoth(scene, cam, 320, 180);
  auto j = judgePixels(scene, cam, f.visbuf, f.forward);
  ASSERT_TRUE(j.ok()) << j.error().message;
  printJudgement("textured city", *j);
  EXPECT_EQ(j->judged, j->covered);
  EXPECT_LE(j->visbuf.maxAbs, 3e-3);
  EXPECT_GE(j->visbuf.psnr, 65.0);
}

// A normal-mapped asset with mesh tangents, mirrored uvs and both sidednesses (NormalTangentMirrorTest), its
// textures baked uncompressed (BC texels are decoded at each device's own precision: texture_reference.h). The
// judge's tangent frame and normal map must agree with both paths. Measured on lavapipe (2026-11) at 256x256: visbuf
// max 1.5e-3, 70.7 dB; forward max 5.8e-3, 70.3 dB. Bounds: twice the visbuf path's largest error, 5 dB under its
// PSNR.
GPU_TEST(PixelJudge, JudgesANormalMappedAsset) {
  SKIP_WITHOUT_OIIO();
  Result<ImportedScene> imported =
      importGltfScene(test::assetPath("NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf").string());
  ASSERT_TRUE(imported) << imported.error().message;
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene) << scene.error().message;
  TextureBakeOptions options;
  options.encoding = TextureEncoding::Rgba8;
  ASSERT_TRUE(bakeTextures(*imported, options, &scene.value()));
  ASSERT_FALSE(scene->materials.empty());
  ASSERT_GE(scene->materials[0].normalTexture.baked, 0) << "the asset is normal-mapped";
  const Frames f = renderBoth(*scene, scene->defaultCamera, 256, 256);
  auto j = judgePixels(*scene, scene->defaultCamera, f.visbuf, f.forward);
  ASSERT_TRUE(j.ok()) << j.error().message;
  printJudgement("normal-mapped asset", *j);
  EXPECT_GT(j->covered, size_t(256 * 256 / 10));
  EXPECT_EQ(j->judged, j->covered);
  EXPECT_LE(j->visbuf.maxAbs, 3e-3);
  EXPECT_GE(j->visbuf.psnr, 65.0);
}
