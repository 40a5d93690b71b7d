// Animated meshes: the compute skinning pass against an independent reference (the same poses skinned on the
// CPU in double precision, drawn by the forward path as static meshes), culling on an animated path, and the
// "skip what is not needed" rules (static scenes record no skinning; a paused pose is not re-skinned).
#include <filesystem>

#include <glm/gtc/matrix_transform.hpp>

#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/asset/texture_bake.h"
#include "../unit/test_assets.h"
#include "cpu_skinning.h"
#include "gpu_test_util.h"
#include "visbuf/scene/animation.h"
#include "visbuf/scene/generate.h"

using namespace visbuf;

namespace {

std::string assetPath(const std::string& rel) { return test::assetPath(rel).string(); }

Result<Scene> loadAsset(const std::string& rel) {
  auto imported = importGltfScene(assetPath(rel));
  if (!imported) return imported.error();
  return buildImportedScene(*imported);
}

}  // namespace

// CesiumMan, Fox (no normals, no indices) and RiggedFigure at several times: visbuf with GPU skinning against
// the CPU-skinned meshes (double precision, drawn as static meshes), same camera, twice:
//  - against the forward path (the accuracy reference): PSNR >= 60 dB, at most 0.1 % of the pixels with a
//    different triangle at silhouettes (float GPU vs double CPU skinning can move an edge across a pixel
//    centre), and without such pixels a max error at most 2e-3 (the Shading tests' bound) above the static
//    scene's own visbuf-vs-forward difference, so that skinning adds no more than the bound to it. (On the H100
//    that difference alone is 0.0028-0.0100 on CesiumMan, skinning or not -- the same visbuf/forward divergence
//    that fails three Shading tests there -- while GPU-skinned visbuf is within 0.0005 of CPU-skinned visbuf.)
//  - against visbuf drawing the CPU-skinned meshes: the same path, so only the skinning differs: the same
//    triangle bound, and max 2e-3.
namespace {

// The body of the test below for one scene (`a` names it in messages) at `times`.
void expectMatchesCpuSkinned(const std::string& a, const Scene* scene, std::initializer_list<double> times) {
  gpu::Device& dev = test::testDevice();
  auto differentTriangles = [](const FrameResult& x, const FrameResult& y) {
    size_t n = 0;
    for (size_t i = 0; i < x.ids.size(); i += 2) n += x.ids[i] != y.ids[i] || x.ids[i + 1] != y.ids[i + 1];
    return n;
  };
  {
    ASSERT_FALSE(scene->skinnedObjects.empty()) << a;
    auto r = Renderer::create(dev, *scene, {.width = 256, .height = 256});
    ASSERT_TRUE(r.ok()) << r.error().message;
    for (double t : times) {
      FrameOptions fo;
      fo.lodErrorPixels = 0.0f;
      fo.readIds = true;
      fo.animationTime = t;
      auto gpuFrame = (*r)->renderFrame(scene->defaultCamera, fo);
      ASSERT_TRUE(gpuFrame.ok()) << gpuFrame.error().message;
      EXPECT_TRUE(gpuFrame->stats.skin.ran);
      const Scene reference = test::cpuSkinned(*scene, t);
      auto rr = Renderer::create(dev, reference, {.width = 256, .height = 256});
      ASSERT_TRUE(rr.ok()) << rr.error().message;
      auto refVisbuf = (*rr)->renderFrame(scene->defaultCamera, fo);
      FrameOptions ro = fo;
      ro.path = RenderPath::Forward;
      ro.cull = CullMode::None;
      auto refFrame = (*rr)->renderFrame(scene->defaultCamera, ro);
      ASSERT_TRUE(refFrame.ok() && refVisbuf.ok());
      size_t covered = 0;
      for (size_t i = 0; i < refFrame->ids.size(); i += 2) covered += refFrame->ids[i] != 0;
      const size_t differentTriangle = differentTriangles(*gpuFrame, *refFrame);
      const size_t differentSamePath = differentTriangles(*gpuFrame, *refVisbuf);
      const test::ImageError e = test::compareColor(gpuFrame->color, refFrame->color);
      const test::ImageError samePath = test::compareColor(gpuFrame->color, refVisbuf->color);
      const test::ImageError staticPaths = test::compareColor(refVisbuf->color, refFrame->color);
      std::printf("%s t=%.2f: %zu px covered; vs forward: %zu with another triangle, max %.5f, PSNR %.1f dB (static "
                  "scene visbuf vs forward: max %.5f); vs visbuf of the CPU-skinned meshes: %zu, max %.5f, PSNR %.1f dB\n",
                  a.c_str(), t, covered, differentTriangle, e.maxAbs, e.psnr, staticPaths.maxAbs, differentSamePath,
                  samePath.maxAbs, samePath.psnr);
      EXPECT_GT(covered, 500u) << a;
      EXPECT_LE(double(differentTriangle), 0.001 * 256 * 256) << a << " t " << t;
      EXPECT_LE(double(differentSamePath), 0.001 * 256 * 256) << a << " t " << t;
      EXPECT_GE(e.psnr, 60.0) << a << " t " << t;
      if (differentTriangle == 0) {
        EXPECT_LE(e.maxAbs, staticPaths.maxAbs + 2e-3) << a << " t " << t;
      }
      if (differentSamePath == 0) {
        EXPECT_LE(samePath.maxAbs, 2e-3) << a << " t " << t;
      }
    }
  }
}

// The morph-target assets, with SparseMorphTargets' clip (one key, weight 0: the file never moves it) replaced
// by a ramp from 0 to 1 over a second, so that its sparse target shows.
Result<Scene> loadMorphAsset(const std::string& rel) {
  auto scene = loadAsset(rel);
  if (scene && rel.starts_with("SparseMorphTargets")) {
    AnimationClip& clip = scene->animations.at(0);
    clip.samplers.at(0) = {Interpolation::Linear, 1, {0.0f, 1.0f}, {0.0f, 1.0f}};
    clip.duration = 1.0;
  }
  return scene;
}
const std::vector<std::string> kMorphAssets = {"AnimatedMorphCube/glTF/AnimatedMorphCube.gltf",
                                               "SimpleMorph/glTF/SimpleMorph.gltf",
                                               "SparseMorphTargets/singleBlendshapeCube_sparse.glb"};

}  // namespace

GPU_TEST(Skinning, MatchesCpuSkinnedForwardReference) {
  const std::vector<std::string> assets = {"CesiumMan/glTF/CesiumMan.gltf", "Fox/glTF-Binary/Fox.glb",
                                           "RiggedFigure/glTF/RiggedFigure.gltf"};
  REQUIRE_ASSET(assetPath(assets[0]));
  for (const std::string& a : assets) {
    auto scene = loadAsset(a);
    ASSERT_TRUE(scene.ok()) << a << ": " << scene.error().message;
    expectMatchesCpuSkinned(a, &*scene, {0.0, 0.37, 1.1});
  }
}

// Morph targets drawn: the same comparison for AnimatedMorphCube, SimpleMorph and SparseMorphTargets (morph-only
// meshes, skinned by their one-joint skin): GPU-morphed visbuf against the CPU-morphed meshes (double precision)
// on the forward path and on visbuf, same bounds as above.
GPU_TEST(Skinning, MorphTargetsMatchCpuMorphedForwardReference) {
  REQUIRE_ASSET(assetPath(kMorphAssets[0]));
  for (const std::string& a : kMorphAssets) {
    auto scene = loadMorphAsset(a);
    ASSERT_TRUE(scene.ok()) << a << ": " << scene.error().message;
    ASSERT_GE(scene->skinnedObjects.at(0).morphNode, 0) << a;
    expectMatchesCpuSkinned(a, &*scene, {0.0, 0.6, 1.45});
  }
}

// GPU-morphed vertices read back against the CPU's double-precision morph (morphVertex), then skinning (the
// one-joint skin of these morph-only meshes, i.e. their node transform), for the three morph assets, 3
// instances each at their own phase (makeAnimatedField), at 5 times. AnimatedMorphCube's tangents are replaced
// by ones perpendicular to each normal, with both handednesses, and given tangent deltas (the file's tangents
// are axis-aligned and its tangent deltas zero, which would check the tangent morph only trivially). Bounds:
// positions 1e-5 of the rest radius scaled by the pose's largest joint scale, normals and tangents 2e-4 (as
// TangentsMatchCpuDoubleSkinning). The weights must move the mesh: some vertex at some time at least 1 % of
// that radius away from the unmorphed base, or the comparison could not tell morphing from no morphing.
GPU_TEST(Skinning, MorphTargetsMatchCpuDoubleReference) {
  REQUIRE_ASSET(assetPath(kMorphAssets[0]));
  for (const std::string& a : kMorphAssets) {
    auto asset = loadMorphAsset(a);
    ASSERT_TRUE(asset.ok()) << a << ": " << asset.error().message;
    if (a.starts_with("AnimatedMorphCube")) {
      Mesh& m = asset->meshes[asset->objects[asset->skinnedObjects[0].object].mesh];
      m.tangents.resize(m.vertices.size());
      for (size_t v = 0; v < m.vertices.size(); ++v) {
        const glm::dvec3 n = glm::dvec3(octDecode(m.vertices[v].normal));
        const glm::dvec3 axis = std::abs(n.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
        m.tangents[v] = glm::vec4(glm::vec3(glm::normalize(glm::cross(axis, n))), v % 2 ? -1.0f : 1.0f);
      }
      for (gpu::MorphDelta& d : m.morphDeltas) d.tx = 3.0f * d.py, d.ty = 3.0f * d.pz, d.tz = 3.0f * d.px;
    }
    auto field = makeAnimatedField(*asset, {.instances = 3, .seed = 13, .spacing = 2.0});
    ASSERT_TRUE(field.ok()) << field.error().message;
    auto r = Renderer::create(dev, *field, {.width = 64, .height = 64});
    ASSERT_TRUE(r.ok()) << r.error().message;
    double maxPosition = 0.0, maxNormal = 0.0, maxTangent = 0.0, moved = 0.0;
    size_t checked = 0, tangents = 0;
    for (double t : {0.0, 0.3, 0.77, 1.6, 2.9}) {
      FrameOptions fo;
      fo.animationTime = t;
      fo.readColor = false;
      ASSERT_TRUE((*r)->renderFrame(field->defaultCamera, fo).ok());
      for (uint32_t i = 0; i < field->skinnedObjects.size(); ++i) {
        const SkinnedObject& so = field->skinnedObjects[i];
        const Mesh& mesh = field->meshes[field->objects[so.object].mesh];
        ASSERT_GT(mesh.morphTargetCount, 0u) << a;
        auto back = (*r)->readSkinnedInstance(i);
        ASSERT_TRUE(back.ok()) << back.error().message;
        ASSERT_EQ(back->vertices.size(), mesh.vertices.size());
        const std::vector<glm::dmat4> joints = skinnedObjectJoints(*field, so, t);
        const std::vector<double> weights = skinnedObjectMorphWeights(*field, so, t);
        double scale = 0.0;  // the rest radius in the skinned (world) units: AnimatedMorphCube's node scales by 100
        for (const glm::dmat4& j : joints) scale = std::max(scale, maxScaleOf(j));
        const double radius = mesh.boundsSphere.w * scale;
        for (uint32_t v = 0; v < mesh.vertices.size(); ++v) {
          const MorphedVertex m = morphVertex(mesh, v, weights);
          const SkinVertex& sv = mesh.skinVertices[v];
          const gpu::SkinnedVertex& s = back->vertices[v];
          const glm::dvec3 p = skinPosition(m.position, sv, joints);
          maxPosition = std::max(maxPosition, glm::length(glm::dvec3(s.px, s.py, s.pz) - p) / radius);
          const glm::dvec3 n = skinNormal(m.normal, sv, joints);
          maxNormal = std::max(maxNormal, glm::length(glm::dvec3(octDecode(s.normal)) - n));
          const gpu::Vertex& base = mesh.vertices[v];
          moved = std::max(moved, glm::length(skinPosition(glm::dvec3(base.px, base.py, base.pz), sv, joints) - p) / radius);
          if (!mesh.tangents.empty()) {
            ASSERT_EQ(back->tangents.size(), mesh.vertices.size());
            const glm::dvec3 want = skinTangent(m.tangent, sv, joints);
            maxTangent = std::max(maxTangent, glm::length(glm::dvec3(octDecode(back->tangents[v])) - want));
            ++tangents;
          }
          ++checked;
        }
      }
    }
    std::printf("%s: %zu vertices (%zu tangents) vs CPU double morph + skin: position %.2e of the radius, normal "
                "%.2e, tangent %.2e; largest morph displacement %.3f of the radius\n",
                a.c_str(), checked, tangents, maxPosition, maxNormal, maxTangent, moved);
    EXPECT_LE(maxPosition, 1e-5) << a;
    EXPECT_LE(maxNormal, 2e-4) << a;
    EXPECT_LE(maxTangent, 2e-4) << a;
    EXPECT_GE(moved, 0.01) << a;
    EXPECT_EQ(tangents > 0, a.starts_with("AnimatedMorphCube")) << a;
  }
}

// The occlusion-culling guarantee on an animated path: 60 animated Foxes, 24 frames with the animation
// advancing and the camera moving, LOD off: the ID image with two-phase occlusion culling equals the one
// with no culling on every frame (a bound that missed a skinned vertex would drop pixels here), with either
// kind of skinned bounds (joint reach, GPU AABB).
GPU_TEST(Skinning, IdImageUnchangedByCullingOnAnimatedPath) {
  REQUIRE_ASSET(assetPath("Fox/glTF-Binary/Fox.glb"));
  auto fox = loadAsset("Fox/glTF-Binary/Fox.glb");
  ASSERT_TRUE(fox.ok());
  auto field = makeAnimatedField(*fox, {.instances = 60, .seed = 3, .spacing = 1.6});
  ASSERT_TRUE(field.ok()) << field.error().message;
  auto plain = Renderer::create(dev, *field, {.width = 240, .height = 160});
  ASSERT_TRUE(plain.ok());
  for (SkinBounds kind : {SkinBounds::Joints, SkinBounds::Gpu}) {
    auto culled = Renderer::create(dev, *field, {.width = 240, .height = 160, .skinBounds = kind});
    ASSERT_TRUE(culled.ok());
    size_t covered = 0, culledObjects = 0;
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
      culledObjects += a1->stats.cull.frustumCulled + a1->stats.cull.occlusionCulled;
      EXPECT_EQ(mismatch, 0u) << skinBoundsName(kind) << " frame " << f;
    }
    std::printf("%s bounds: %zu objects culled over 24 frames\n", skinBoundsName(kind), culledObjects);
    EXPECT_GT(covered, 24u * 500u);
  }
}

// Classified shading reads the skinned vertices too: RiggedFigure (skinned, untextured, so the classified pass uses
// its untextured pipeline) mid-animation, classified against the ubershader, same frame: the same image, and a pose
// that moved from the rest pose (the rest vertices would shade another image).
GPU_TEST(Skinning, ClassifiedShadingOfSkinnedMeshEqualsUbershader) {
  REQUIRE_ASSET(assetPath("RiggedFigure/glTF/RiggedFigure.gltf"));
  auto scene = loadAsset("RiggedFigure/glTF/RiggedFigure.gltf");
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  auto r = Renderer::create(dev, *scene, {.width = 200, .height = 200});
  ASSERT_TRUE(r.ok()) << r.error().message;
  FrameOptions fo;
  fo.animationTime = 0.0;
  auto rest = (*r)->renderFrame(scene->defaultCamera, fo);
  fo.animationTime = 0.6;
  auto uber = (*r)->renderFrame(scene->defaultCamera, fo);
  fo.shading = ShadingMode::Classified;
  auto classified = (*r)->renderFrame(scene->defaultCamera, fo);
  ASSERT_TRUE(rest.ok() && uber.ok() && classified.ok());
  EXPECT_EQ(classified->stats.shade.mode, ShadingMode::Classified);
  EXPECT_GT(uber->stats.coveredPixels, 1000u);
  EXPECT_EQ(test::compareColor(classified->color, uber->color).maxAbs, 0.0);
  EXPECT_GT(test::compareColor(rest->color, uber->color).maxAbs, 0.1) << "the pose must move";
}

// Skip what the scene does not need: a static scene records no skinning pass (and has no skinning state);
// an animated one re-skins only when the pose changes, and a paused frame is identical to the one before.
GPU_TEST(Skinning, StaticScenesAndPausedPosesRecordNoSkinning) {
  FieldParams p;
  p.objects = 50;
  p.mesh = makeTorusKnot(32, 8);
  auto still = makeFieldScene(p);
  ASSERT_TRUE(still.ok());
  auto rs = Renderer::create(dev, *still, {.width = 64, .height = 64});
  ASSERT_TRUE(rs.ok());
  auto fs = (*rs)->renderFrame(still->defaultCamera, {});
  ASSERT_TRUE(fs.ok());
  EXPECT_EQ(fs->stats.skin.instances, 0u);
  EXPECT_FALSE(fs->stats.skin.ran);
  for (const auto& [name, ms] : fs->stats.graph.passMs) EXPECT_NE(name, "skin");

  REQUIRE_ASSET(assetPath("Fox/glTF-Binary/Fox.glb"));
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
    for (const auto& [name, ms] : s.graph.passMs)
      if (name == "skin") return true;
    return false;
  };
  EXPECT_TRUE(f1->stats.skin.ran && hasSkin(f1->stats));
  EXPECT_FALSE(f2->stats.skin.ran || hasSkin(f2->stats));
  EXPECT_TRUE(f3->stats.skin.ran && hasSkin(f3->stats));
  EXPECT_EQ(f1->color, f2->color);
  EXPECT_NE(f2->color, f3->color);
}

// Many instances: 3,000 animated Foxes (4.5M skinned vertices, 72 MB of regions read by device address; the
// CPU-skinned reference scene's copies fill the vertex pool past one lavapipe descriptor window of 2^22
// vertices). Every region must land where its mesh slot says: IDs equal to the reference's, and the shading
// within the first test's bound.
GPU_TEST(Skinning, PoolAcrossVertexWindowsMatchesCpuSkinning) {
  REQUIRE_ASSET(assetPath("Fox/glTF-Binary/Fox.glb"));
  auto fox = loadAsset("Fox/glTF-Binary/Fox.glb");
  ASSERT_TRUE(fox.ok());
  auto field = makeAnimatedField(*fox, {.instances = 3000, .seed = 5, .spacing = 1.5});
  ASSERT_TRUE(field.ok());
  auto r = Renderer::create(dev, *field, {.width = 200, .height = 120});
  ASSERT_TRUE(r.ok()) << r.error().message;
  FrameOptions fo;
  fo.lodErrorPixels = 0.0f;
  fo.readIds = true;
  fo.animationTime = 0.8;
  auto f = (*r)->renderFrame(field->defaultCamera, fo);
  ASSERT_TRUE(f.ok());
  const Scene reference = test::cpuSkinned(*field, 0.8);
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
              (unsigned long long)f->stats.skin.vertices, covered, different, e.psnr);
  EXPECT_GT(f->stats.skin.vertices, uint64_t(1) << 22);  // the reference: more than one lavapipe window
  EXPECT_GT(covered, 2000u);
  EXPECT_LE(double(different), 0.001 * 200 * 120);
  EXPECT_GE(e.psnr, 60.0);
}

namespace {

// Gives every vertex of every skinned mesh a tangent: a unit vector perpendicular to its normal (any such
// vector is a valid tangent frame), handedness alternating +1 / -1 so that both signs travel.
void addTangents(Scene& scene) {
  for (const SkinnedObject& so : scene.skinnedObjects) {
    Mesh& m = scene.meshes[scene.objects[so.object].mesh];
    if (!m.tangents.empty()) continue;
    m.tangents.resize(m.vertices.size());
    for (size_t v = 0; v < m.vertices.size(); ++v) {
      const glm::dvec3 n = glm::dvec3(octDecode(m.vertices[v].normal));
      const glm::dvec3 axis = std::abs(n.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
      m.tangents[v] = glm::vec4(glm::vec3(glm::normalize(glm::cross(axis, n))), v % 2 ? -1.0f : 1.0f);
    }
  }
}

}  // namespace

// Skinned tangents against the CPU's double-precision skinning (skinTangent: the blended 3x3 applied to the
// rest tangent, normalised). CesiumMan with a tangent on every vertex, 3 instances at their own phases, 3
// times; the GPU's tangents are read back (octahedral, 2 x 16 bits) and compared as unit vectors. Bound: 2e-4
// (two octahedral quantisations of about 5e-5 each -- the rest tangent's and the result's -- plus float
// blending); the positions are checked against the same reference to 1e-5 of the mesh's radius.
GPU_TEST(Skinning, TangentsMatchCpuDoubleSkinning) {
  REQUIRE_ASSET(assetPath("CesiumMan/glTF/CesiumMan.gltf"));
  auto man = loadAsset("CesiumMan/glTF/CesiumMan.gltf");
  ASSERT_TRUE(man.ok());
  addTangents(*man);
  auto field = makeAnimatedField(*man, {.instances = 3, .seed = 7, .spacing = 2.0});
  ASSERT_TRUE(field.ok()) << field.error().message;
  auto r = Renderer::create(dev, *field, {.width = 64, .height = 64});
  ASSERT_TRUE(r.ok()) << r.error().message;
  for (double t : {0.0, 0.45, 1.3}) {
    FrameOptions fo;
    fo.animationTime = t;
    fo.readColor = false;
    ASSERT_TRUE((*r)->renderFrame(field->defaultCamera, fo).ok());
    double maxTangent = 0.0, maxPosition = 0.0;
    size_t checked = 0;
    for (uint32_t i = 0; i < field->skinnedObjects.size(); ++i) {
      const SkinnedObject& so = field->skinnedObjects[i];
      const Mesh& mesh = field->meshes[field->objects[so.object].mesh];
      auto back = (*r)->readSkinnedInstance(i);
      ASSERT_TRUE(back.ok()) << back.error().message;
      ASSERT_EQ(back->tangents.size(), mesh.vertices.size());
      const std::vector<glm::dmat4> joints = skinnedObjectJoints(*field, so, t);
      for (size_t v = 0; v < mesh.vertices.size(); ++v) {
        const glm::dvec3 want = skinTangent(glm::dvec3(mesh.tangents[v]), mesh.skinVertices[v], joints);
        maxTangent = std::max(maxTangent, glm::length(glm::dvec3(octDecode(back->tangents[v])) - want));
        const gpu::Vertex& rest = mesh.vertices[v];
        const glm::dvec3 p = skinPosition(glm::dvec3(rest.px, rest.py, rest.pz), mesh.skinVertices[v], joints);
        const gpu::SkinnedVertex& s = back->vertices[v];
        maxPosition = std::max(maxPosition, glm::length(glm::dvec3(s.px, s.py, s.pz) - p) / mesh.boundsSphere.w);
        ++checked;
      }
    }
    std::printf("t=%.2f: %zu tangents, max |t - t_cpu| %.2e; positions max error %.2e of the radius\n", t, checked,
                maxTangent, maxPosition);
    EXPECT_LE(maxTangent, 2e-4) << "t " << t;
    EXPECT_LE(maxPosition, 1e-5) << "t " << t;
  }
}

// Culling bounds of skinned instances contain every skinned vertex, for both kinds: the joints' reach (CPU;
// for morph targets widened by sum |w| max |delta|) and the GPU's AABB reduction. Every vertex the skinning pass
// wrote is read back with its instance's sphere and tested in double precision (|p - c| <= r, no tolerance),
// for 24 Foxes, CesiumMan, RiggedFigure, 24 AnimatedMorphCubes and 24 SparseMorphTargets cubes at 5 times each. Also prints how tight each kind is: the mean of radius / (the largest distance of the instance's
// vertices from their AABB centre), which is 1 for the tightest sphere about that centre.
GPU_TEST(Skinning, BoundsContainEverySkinnedVertex) {
  REQUIRE_ASSET(assetPath("Fox/glTF-Binary/Fox.glb"));
  std::vector<std::pair<std::string, Scene>> scenes;
  for (const char* a : {"Fox/glTF-Binary/Fox.glb", "CesiumMan/glTF/CesiumMan.gltf", "RiggedFigure/glTF/RiggedFigure.gltf",
                        "AnimatedMorphCube/glTF/AnimatedMorphCube.gltf", "SparseMorphTargets/singleBlendshapeCube_sparse.glb"}) {
    auto s = loadMorphAsset(a);
    ASSERT_TRUE(s.ok()) << a;
    if (std::string(a).starts_with("Fox") || s->meshes[0].morphTargetCount > 0) {  // morph cubes: 24 vertices each
      auto field = makeAnimatedField(*s, {.instances = 24, .seed = 11, .spacing = 1.6});
      ASSERT_TRUE(field.ok());
      s = std::move(field);
    }
    scenes.emplace_back(a, std::move(*s));
  }
  for (SkinBounds kind : {SkinBounds::Joints, SkinBounds::Gpu}) {
    for (const auto& [name, scene] : scenes) {
      auto r = Renderer::create(dev, scene, {.width = 64, .height = 64, .skinBounds = kind});
      ASSERT_TRUE(r.ok()) << r.error().message;
      size_t vertices = 0, outside = 0, spheres = 0;
      double ratio = 0.0, worst = 0.0;
      for (double t : {0.0, 0.29, 0.8, 1.7, 3.1}) {
        FrameOptions fo;
        fo.animationTime = t;
        fo.readColor = false;
        ASSERT_TRUE((*r)->renderFrame(scene.defaultCamera, fo).ok());
        for (uint32_t i = 0; i < scene.skinnedObjects.size(); ++i) {
          auto back = (*r)->readSkinnedInstance(i);
          ASSERT_TRUE(back.ok());
          const glm::dvec3 c(back->bounds);
          const double radius = back->bounds.w;
          glm::dvec3 lo(INFINITY), hi(-INFINITY);
          for (const gpu::SkinnedVertex& v : back->vertices) {
            const glm::dvec3 p(v.px, v.py, v.pz);
            const double d = glm::length(p - c);
            outside += !(d <= radius);
            worst = std::max(worst, d / radius);
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
          }
          double reach = 0.0;
          for (const gpu::SkinnedVertex& v : back->vertices)
            reach = std::max(reach, glm::length(glm::dvec3(v.px, v.py, v.pz) - 0.5 * (lo + hi)));
          ratio += radius / reach;
          ++spheres;
          vertices += back->vertices.size();
        }
      }
      std::printf("%s bounds, %s: %zu vertices in %zu spheres, %zu outside, largest |p - c| / r %.6f, mean radius / "
                  "tightest radius about the AABB centre %.3f\n",
                  skinBoundsName(kind), name.c_str(), vertices, spheres, outside, worst, ratio / double(spheres));
      EXPECT_EQ(outside, 0u) << skinBoundsName(kind) << " " << name;
      EXPECT_GT(vertices, 1000u);
    }
  }
}

// Skinned tangents where they are used: a normal-mapped skinned mesh. CesiumMan with its textures baked, a tangent
// on every vertex (addTangents) and its base colour texture also bound as the normal map (any texture is a valid
// perturbation; this one has sharp, high-contrast edges). GPU skinning is compared with the CPU-skinned meshes
// (double precision, tangents included) drawn by the same path, for the visbuf path (shade.comp reads the skinned
// tangents) and the forward path (forward.vert): at most 0.1 % of the pixels on another triangle and, without
// such pixels, max 2e-3. The normal map must matter: without it the image differs by more than 0.05.
GPU_TEST(Skinning, NormalMappedSkinnedMeshMatchesCpuSkinning) {
  const std::string file = assetPath("CesiumMan/glTF/CesiumMan.gltf");
  REQUIRE_ASSET(file);
  auto imported = importGltfScene(file);
  ASSERT_TRUE(imported.ok());
  auto man = buildImportedScene(*imported);
  ASSERT_TRUE(man.ok());
  TextureBakeOptions small;
  small.maxTextureSize = 256;  // the texture's edges are what matters, not its size (and baking time)
  SKIP_WITHOUT_OIIO();  // what follows bakes the textures
  Status baked = bakeTextures(*imported, small, &man.value());
  ASSERT_TRUE(baked.ok()) << baked.error().message;
  Scene plain = *man;
  addTangents(*man);
  for (Material& m : man->materials) {
    ASSERT_GE(m.baseColorTexture.baked, 0);
    m.normalTexture = m.baseColorTexture;
  }
  const RendererConfig rc{.width = 256, .height = 256};
  auto r = Renderer::create(dev, *man, rc);
  auto rPlain = Renderer::create(dev, plain, rc);
  ASSERT_TRUE(r.ok() && rPlain.ok()) << (r.ok() ? rPlain.error().message : r.error().message);
  for (double t : {0.8}) {  // one pose: every textured renderer costs seconds of shader compilation on lavapipe
    const Scene reference = test::cpuSkinned(*man, t);
    auto rr = Renderer::create(dev, reference, rc);
    ASSERT_TRUE(rr.ok()) << rr.error().message;
    for (RenderPath path : {RenderPath::Visbuf, RenderPath::Forward}) {
      FrameOptions fo;
      fo.path = path;
      fo.lodErrorPixels = 0.0f;
      fo.readIds = true;
      fo.animationTime = t;
      auto f = (*r)->renderFrame(man->defaultCamera, fo);
      auto g = (*rr)->renderFrame(man->defaultCamera, fo);
      auto h = (*rPlain)->renderFrame(man->defaultCamera, fo);
      ASSERT_TRUE(f.ok() && g.ok() && h.ok());
      size_t different = 0;
      for (size_t i = 0; i < f->ids.size(); i += 2) different += f->ids[i] != g->ids[i] || f->ids[i + 1] != g->ids[i + 1];
      const test::ImageError e = test::compareColor(f->color, g->color);
      const test::ImageError mapped = test::compareColor(f->color, h->color);
      std::printf("%s t=%.2f: %zu px on another triangle, max %.5f, PSNR %.1f dB; without the normal map: max %.3f\n",
                  renderPathName(path), t, different, e.maxAbs, e.psnr, mapped.maxAbs);
      EXPECT_LE(double(different), 0.001 * 256 * 256) << renderPathName(path) << " t " << t;
      if (different == 0) {
        EXPECT_LE(e.maxAbs, 2e-3) << renderPathName(path) << " t " << t;
      }
      EXPECT_GT(mapped.maxAbs, 0.05) << renderPathName(path) << " t " << t;
    }
  }
}
