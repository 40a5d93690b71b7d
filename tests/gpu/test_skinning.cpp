// Animated meshes: the compute skinning pass against an independent reference (the same poses skinned on the
// CPU in double precision, drawn by the forward path as static meshes), culling on an animated path, and the
// "skip what is not needed" rules (static scenes record no skinning; a paused pose is not re-skinned).
#include <filesystem>

#include <glm/gtc/matrix_transform.hpp>

#include "asset/gltf_import.h"
#include "asset/scene_bake.h"
#include "gpu_test_util.h"
#include "scene/animation.h"
#include "scene/generate.h"

using namespace visbuf;

namespace {

std::string assetPath(const std::string& rel) { return std::string(VISBUF_SHARED_ASSETS_DIR) + "/" + rel; }

Result<Scene> loadAsset(const std::string& rel) {
  auto imported = importGltfScene(assetPath(rel));
  if (!imported) return imported.error();
  return buildImportedScene(*imported);
}

// The scene at `time` with every skinned object replaced by a static copy of its mesh, skinned on the CPU in
// double precision (animation.h), placed by its placement; no animation data left. Shares no code with the
// GPU path beyond the pose evaluation (clip sampling and joint matrices).
Scene cpuSkinned(const Scene& animated, double time) {
  Scene s = animated;
  s.nodes.clear();
  s.skins.clear();
  s.animations.clear();
  s.skinnedObjects.clear();
  for (const SkinnedObject& so : animated.skinnedObjects) {
    Pose pose = restPose(animated.nodes);
    if (so.clip >= 0 && size_t(so.clip) < animated.animations.size())
      sampleClip(animated.animations[size_t(so.clip)], time + so.timeOffset, true, pose);
    const std::vector<glm::dmat4> joints =
        jointMatrices(animated.skins[so.skin], globalMatrices(animated.nodes, pose));
    const Object& o = animated.objects[so.object];
    Mesh m = animated.meshes[o.mesh];
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (size_t v = 0; v < m.vertices.size(); ++v) {
      gpu::Vertex& vert = m.vertices[v];
      const glm::dvec3 p = skinPosition(glm::dvec3(vert.px, vert.py, vert.pz), m.skinVertices[v], joints);
      const glm::dvec3 n = skinNormal(glm::dvec3(octDecode(vert.normal)), m.skinVertices[v], joints);
      vert.px = float(p.x);
      vert.py = float(p.y);
      vert.pz = float(p.z);
      vert.normal = octEncode(glm::vec3(n));
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    m.skinVertices.clear();
    m.boundsSphere = glm::vec4(glm::vec3(0.5 * (lo + hi)), float(0.5 * glm::length(hi - lo)) * 1.0001f);
    s.objects[so.object].mesh = uint32_t(s.meshes.size());
    s.objects[so.object].transform = so.placement;
    s.meshes.push_back(std::move(m));
  }
  return s;
}

}  // namespace

// CesiumMan, Fox (no normals, no indices) and RiggedFigure at several times: visbuf with GPU skinning vs the
// forward path drawing the CPU-skinned meshes, same camera. Bound: the Shading tests' (max 2e-3 per channel,
// PSNR >= 80 dB), with at most 0.1 % of the pixels allowed a different triangle at silhouettes (float GPU vs
// double CPU skinning can move an edge across a pixel centre).
TEST(Skinning, MatchesCpuSkinnedForwardReference) {
  const std::vector<std::string> assets = {"CesiumMan/glTF/CesiumMan.gltf", "Fox/glTF-Binary/Fox.glb",
                                           "RiggedFigure/glTF/RiggedFigure.gltf"};
  if (!std::filesystem::exists(assetPath(assets[0]))) GTEST_SKIP() << "shared assets not present";
  gpu::Device& dev = test::testDevice();
  const uint32_t before = dev.validationMessages();
  for (const std::string& a : assets) {
    auto scene = loadAsset(a);
    ASSERT_TRUE(scene.ok()) << a << ": " << scene.error().message;
    ASSERT_FALSE(scene->skinnedObjects.empty()) << a;
    auto r = Renderer::create(dev, *scene, {.width = 256, .height = 256});
    ASSERT_TRUE(r.ok()) << r.error().message;
    for (double t : {0.0, 0.37, 1.1}) {
      FrameOptions fo;
      fo.lodErrorPixels = 0.0f;
      fo.readIds = true;
      fo.animationTime = t;
      auto gpuFrame = (*r)->renderFrame(scene->defaultCamera, fo);
      ASSERT_TRUE(gpuFrame.ok()) << gpuFrame.error().message;
      EXPECT_TRUE(gpuFrame->stats.skinned);
      const Scene reference = cpuSkinned(*scene, t);
      auto rr = Renderer::create(dev, reference, {.width = 256, .height = 256});
      ASSERT_TRUE(rr.ok()) << rr.error().message;
      FrameOptions ro = fo;
      ro.path = RenderPath::Forward;
      ro.cull = CullMode::None;
      auto refFrame = (*rr)->renderFrame(scene->defaultCamera, ro);
      ASSERT_TRUE(refFrame.ok());
      size_t covered = 0, differentTriangle = 0;
      for (size_t i = 0; i < gpuFrame->ids.size(); i += 2) {
        covered += refFrame->ids[i] != 0;
        differentTriangle += gpuFrame->ids[i] != refFrame->ids[i] || gpuFrame->ids[i + 1] != refFrame->ids[i + 1];
      }
      const test::ImageError e = test::compareColor(gpuFrame->color, refFrame->color);
      std::printf("%s t=%.2f: %zu px covered, %zu with another triangle, max %.5f, PSNR %.1f dB\n", a.c_str(), t,
                  covered, differentTriangle, e.maxAbs, e.psnr);
      EXPECT_GT(covered, 500u) << a;
      EXPECT_LE(double(differentTriangle), 0.001 * 256 * 256) << a << " t " << t;
      EXPECT_GE(e.psnr, 60.0) << a << " t " << t;
      if (differentTriangle == 0) {
        EXPECT_LE(e.maxAbs, 2e-3) << a << " t " << t;
      }
    }
  }
  EXPECT_NO_VALIDATION_MESSAGES(before);
}

// The occlusion-culling guarantee on an animated path: 60 animated Foxes, 24 frames with the animation
// advancing and the camera moving, LOD off: the ID image with two-phase occlusion culling equals the one
// with no culling on every frame (a bound that missed a skinned vertex would drop pixels here).
TEST(Skinning, IdImageUnchangedByCullingOnAnimatedPath) {
  if (!std::filesystem::exists(assetPath("Fox/glTF-Binary/Fox.glb"))) GTEST_SKIP() << "shared assets not present";
  auto fox = loadAsset("Fox/glTF-Binary/Fox.glb");
  ASSERT_TRUE(fox.ok());
  auto field = makeAnimatedField(*fox, {.instances = 60, .seed = 3, .spacing = 1.6});
  ASSERT_TRUE(field.ok()) << field.error().message;
  gpu::Device& dev = test::testDevice();
  const uint32_t before = dev.validationMessages();
  auto culled = Renderer::create(dev, *field, {.width = 240, .height = 160});
  auto plain = Renderer::create(dev, *field, {.width = 240, .height = 160});
  ASSERT_TRUE(culled.ok() && plain.ok());
  size_t covered = 0;
  for (int f = 0; f < 24; ++f) {
    Camera cam = field->defaultCamera;
    const double a = 0.05 * f;
    cam.position = glm::dvec3(glm::rotate(glm::dmat4(1.0), a, glm::dvec3(0, 1, 0)) * glm::dvec4(cam.position, 1.0));
    FrameOptions fo;
    fo.lodErrorPixels = 0.0f;
    fo.readIds = true;
    fo.animationTime = 0.1 * f;
    auto a1 = (*culled)->renderFrame(cam, fo);
    fo.cull = CullMode::None;
    auto a2 = (*plain)->renderFrame(cam, fo);
    ASSERT_TRUE(a1.ok() && a2.ok());
    size_t mismatch = 0;
    for (size_t i = 0; i < a1->ids.size(); ++i) mismatch += a1->ids[i] != a2->ids[i];
    for (size_t i = 0; i < a2->ids.size(); i += 2) covered += a2->ids[i] != 0;
    EXPECT_EQ(mismatch, 0u) << "frame " << f;
  }
  EXPECT_GT(covered, 24u * 500u);
  EXPECT_NO_VALIDATION_MESSAGES(before);
}

// Skip what the scene does not need: a static scene records no skinning pass (and has no skinning state);
// an animated one re-skins only when the pose changes, and a paused frame is identical to the one before.
TEST(Skinning, StaticScenesAndPausedPosesRecordNoSkinning) {
  gpu::Device& dev = test::testDevice();
  FieldParams p;
  p.objects = 50;
  p.mesh = makeTorusKnot(32, 8);
  auto still = makeFieldScene(p);
  ASSERT_TRUE(still.ok());
  auto rs = Renderer::create(dev, *still, {.width = 64, .height = 64});
  ASSERT_TRUE(rs.ok());
  auto fs = (*rs)->renderFrame(still->defaultCamera, {});
  ASSERT_TRUE(fs.ok());
  EXPECT_EQ(fs->stats.skinnedInstances, 0u);
  EXPECT_FALSE(fs->stats.skinned);
  for (const auto& [name, ms] : fs->stats.passMs) EXPECT_NE(name, "skin");

  if (!std::filesystem::exists(assetPath("Fox/glTF-Binary/Fox.glb"))) GTEST_SKIP() << "shared assets not present";
  auto fox = loadAsset("Fox/glTF-Binary/Fox.glb");
  ASSERT_TRUE(fox.ok());
  auto ra = Renderer::create(dev, *fox, {.width = 96, .height = 96});
  ASSERT_TRUE(ra.ok());
  FrameOptions fo;
  fo.animationTime = 0.5;
  auto f1 = (*ra)->renderFrame(fox->defaultCamera, fo);
  auto f2 = (*ra)->renderFrame(fox->defaultCamera, fo);  // paused: same time
  fo.animationTime = 0.6;
  auto f3 = (*ra)->renderFrame(fox->defaultCamera, fo);
  ASSERT_TRUE(f1.ok() && f2.ok() && f3.ok());
  auto hasSkin = [](const FrameStats& s) {
    for (const auto& [name, ms] : s.passMs)
      if (name == "skin") return true;
    return false;
  };
  EXPECT_TRUE(f1->stats.skinned && hasSkin(f1->stats));
  EXPECT_FALSE(f2->stats.skinned || hasSkin(f2->stats));
  EXPECT_TRUE(f3->stats.skinned && hasSkin(f3->stats));
  EXPECT_EQ(f1->color, f2->color);
  EXPECT_NE(f2->color, f3->color);
}

// A pool larger than one descriptor window (lavapipe: 2^22 vertices of 128 MiB): 3,000 animated Foxes put
// their regions in two windows, and the CPU-skinned reference scene's copies likewise. Every read and write
// across the boundary must land: IDs equal to the reference's, and the shading within the first test's bound.
TEST(Skinning, PoolAcrossVertexWindowsMatchesCpuSkinning) {
  if (!std::filesystem::exists(assetPath("Fox/glTF-Binary/Fox.glb"))) GTEST_SKIP() << "shared assets not present";
  auto fox = loadAsset("Fox/glTF-Binary/Fox.glb");
  ASSERT_TRUE(fox.ok());
  auto field = makeAnimatedField(*fox, {.instances = 3000, .seed = 5, .spacing = 1.5});
  ASSERT_TRUE(field.ok());
  gpu::Device& dev = test::testDevice();
  const uint32_t before = dev.validationMessages();
  auto r = Renderer::create(dev, *field, {.width = 200, .height = 120});
  ASSERT_TRUE(r.ok()) << r.error().message;
  FrameOptions fo;
  fo.lodErrorPixels = 0.0f;
  fo.readIds = true;
  fo.animationTime = 0.8;
  auto f = (*r)->renderFrame(field->defaultCamera, fo);
  ASSERT_TRUE(f.ok());
  const Scene reference = cpuSkinned(*field, 0.8);
  auto rr = Renderer::create(dev, reference, {.width = 200, .height = 120});
  ASSERT_TRUE(rr.ok());
  fo.path = RenderPath::Forward;
  fo.cull = CullMode::None;
  auto g = (*rr)->renderFrame(field->defaultCamera, fo);
  ASSERT_TRUE(g.ok());
  size_t covered = 0, different = 0;
  for (size_t i = 0; i < f->ids.size(); i += 2) {
    covered += g->ids[i] != 0;
    different += f->ids[i] != g->ids[i] || f->ids[i + 1] != g->ids[i + 1];
  }
  const test::ImageError e = test::compareColor(f->color, g->color);
  std::printf("3000 Foxes, %llu skinned vertices: %zu px covered, %zu differ, PSNR %.1f dB\n",
              (unsigned long long)f->stats.skinnedVertices, covered, different, e.psnr);
  EXPECT_GT(f->stats.skinnedVertices, uint64_t(1) << 22);  // more than one lavapipe window
  EXPECT_GT(covered, 2000u);
  EXPECT_LE(double(different), 0.001 * 200 * 120);
  EXPECT_GE(e.psnr, 60.0);
  EXPECT_NO_VALIDATION_MESSAGES(before);
}
