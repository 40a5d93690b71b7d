// Cameras on the CPU: perspective (aspect fitting, finite far) and orthographic projections against double-precision
// formulas, the camera checks, glTF camera import and its errors, packs keeping the cameras, and the default camera
// framing every animated object over its whole animation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "temp_dir_test.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/render/frame_math.h"
#include "visbuf/scene/scene.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The camera's orthonormal frame (right, up, forward), from its look-at form, in double.
struct Frame {
  glm::dvec3 right, up, forward;
};
Frame frameOf(const Camera& c) {
  Frame f;
  f.forward = glm::normalize(c.target - c.position);
  f.right = glm::normalize(glm::cross(f.forward, c.up));
  f.up = glm::cross(f.right, f.forward);
  return f;
}

Camera orthoCamera() {
  Camera c;
  c.projection = Projection::Orthographic;
  c.position = {3.0, -2.0, 7.0};
  c.target = c.position + glm::dvec3(-0.3, 0.2, -1.0);
  c.up = {0.1, 1.0, 0.0};
  c.xmag = 3.0;
  c.ymag = 2.0;
  c.nearPlane = 0.5;
  c.farPlane = 20.0;
  return c;
}

// Orthographic: ndc = (x / halfX, -y / halfY) and depth = (far - d) / (far - near) for a point at view (x, y, -d); the
// window fitted to the viewport (xmag by ymag at 3:2; wider viewport: more width; taller: more height).
TEST(CameraMath, OrthographicProjectsLikeDoubleMath) {
  const Camera cam = orthoCamera();
  ASSERT_TRUE(validateCamera(cam)) << validateCamera(cam).error().message;
  const Frame f = frameOf(cam);
  struct Case {
    uint32_t w, h;
    double halfX, halfY;
  };
  for (const Case& k : {Case{300, 200, 3.0, 2.0}, Case{400, 200, 4.0, 2.0}, Case{300, 300, 3.0, 3.0}}) {
    const FrameMath fm = computeFrameMath(cam, k.w, k.h);
    EXPECT_TRUE(fm.orthographic);
    EXPECT_NEAR(fm.lodScale, k.h * 0.5 / k.halfY, 1e-9);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.3, 1.3);
    int inside = 0;
    for (int i = 0; i < 2000; ++i) {
      const double x = u(rng) * k.halfX, y = u(rng) * k.halfY, d = 0.5 + (u(rng) + 1.3) / 2.6 * 22.0 - 1.0;
      const glm::dvec3 p = cam.position + x * f.right + y * f.up + d * f.forward;
      const glm::dvec4 clip = fm.viewProj * glm::dvec4(p - cam.position, 1.0);
      ASSERT_EQ(clip.w, 1.0);
      EXPECT_NEAR(clip.x, x / k.halfX, 1e-12);
      EXPECT_NEAR(clip.y, -y / k.halfY, 1e-12);
      EXPECT_NEAR(clip.z, (cam.farPlane - d) / (cam.farPlane - cam.nearPlane), 1e-12);
      const bool in = std::abs(x) <= k.halfX && std::abs(y) <= k.halfY && d >= cam.nearPlane && d <= cam.farPlane;
      const double margin = std::min({k.halfX - std::abs(x), k.halfY - std::abs(y), d - cam.nearPlane,
                                      cam.farPlane - d});
      if (std::abs(margin) < 1e-9) continue;
      EXPECT_EQ(sphereInFrustum(fm, cam, p, 0.0), in) << x << " " << y << " " << d;
      // A sphere's signed distance is the point's, less the radius (unit plane normals).
      EXPECT_EQ(sphereInFrustum(fm, cam, p, std::abs(margin) * 0.5), in);
      inside += in;
    }
    EXPECT_GT(inside, 300);
  }
}

// Perspective with glTF's aspectRatio: the authored window (tan(yfov/2) * aspect by tan(yfov/2)) stays whole in any
// viewport; a finite far plane maps to depth 0 and culls beyond it.
TEST(CameraMath, PerspectiveAspectRatioAndFiniteFar) {
  Camera cam;
  cam.position = {1.0, 2.0, 3.0};
  cam.target = {1.0, 2.0, -5.0};
  cam.fovY = 0.8;
  cam.aspectRatio = 2.0;
  cam.nearPlane = 0.25;
  cam.farPlane = 40.0;
  const double t = std::tan(0.4);
  struct Case {
    uint32_t w, h;
    double halfX, halfY;  // tangents
  };
  for (const Case& k : {Case{200, 100, 2 * t, t}, Case{100, 100, 2 * t, 2 * t}, Case{400, 100, 4 * t, t}}) {
    const FrameMath fm = computeFrameMath(cam, k.w, k.h);
    EXPECT_NEAR(fm.proj[0][0], 1.0 / k.halfX, 1e-12);
    EXPECT_NEAR(fm.proj[1][1], -1.0 / k.halfY, 1e-12);
    EXPECT_NEAR(fm.lodScale, k.h * 0.5 / k.halfY, 1e-9);
    for (double d : {0.25, 1.0, 17.0, 40.0}) {
      const glm::dvec4 c = fm.viewProj * glm::dvec4(0.3 * d, -0.2 * d, -d, 1.0);
      EXPECT_NEAR(c.x / c.w, 0.3 / k.halfX, 1e-12);
      EXPECT_NEAR(c.y / c.w, 0.2 / k.halfY, 1e-12);
      EXPECT_NEAR(c.z / c.w, cam.nearPlane * (cam.farPlane - d) / (d * (cam.farPlane - cam.nearPlane)), 1e-12);
    }
    // The authored corners just inside, the viewport's edge just outside.
    const double d = 10.0;
    EXPECT_TRUE(sphereInFrustum(fm, cam, cam.position + glm::dvec3(0.999 * 2 * t * d, 0.999 * t * d, -d), 0.0));
    EXPECT_FALSE(sphereInFrustum(fm, cam, cam.position + glm::dvec3(1.001 * k.halfX * d, 0.0, -d), 0.0));
    EXPECT_FALSE(sphereInFrustum(fm, cam, cam.position + glm::dvec3(0.0, 1.001 * k.halfY * d, -d), 0.0));
    EXPECT_TRUE(sphereInFrustum(fm, cam, cam.position + glm::dvec3(0.0, 0.0, -39.9), 0.0));
    EXPECT_FALSE(sphereInFrustum(fm, cam, cam.position + glm::dvec3(0.0, 0.0, -40.2), 0.1));
    EXPECT_TRUE(sphereInFrustum(fm, cam, cam.position + glm::dvec3(0.0, 0.0, -40.2), 0.3));
  }
  cam.aspectRatio = 0.0;  // absent: the viewport's, so fovY stays vertical
  EXPECT_NEAR(computeFrameMath(cam, 100, 300).proj[1][1], -1.0 / t, 1e-12);
}

// Orthographic LOD: the projected error does not shrink with distance, so the level is the same at any distance.
TEST(CameraMath, OrthographicLodIgnoresDistance) {
  Mesh mesh;
  mesh.lods = {{0, 3, 0.0f}, {0, 3, 0.01f}, {0, 3, 0.1f}};
  const Camera cam = orthoCamera();
  const FrameMath fm = computeFrameMath(cam, 300, 200);  // 50 pixels per unit
  EXPECT_EQ(selectLod(mesh, 1.0, 0.001, fm, cam.nearPlane, 1.0f), 1u);  // 0.5 px; 5 px
  EXPECT_EQ(selectLod(mesh, 1.0, 1000.0, fm, cam.nearPlane, 1.0f), 1u);
  EXPECT_EQ(selectLod(mesh, 1.0, 1000.0, fm, cam.nearPlane, 6.0f), 2u);  // 5 px <= 6
  EXPECT_EQ(selectLod(mesh, 1.0, 1000.0, fm, cam.nearPlane, 0.0f), 0u);  // LOD off
}

TEST(CameraMath, ValidationNamesTheProblem) {
  struct Bad {
    void (*edit)(Camera&);
    const char* says;
  };
  const Bad bad[] = {
      {[](Camera& c) { c.fovY = std::numbers::pi; }, "field of view"},
      {[](Camera& c) { c.fovY = NAN; }, "field of view"},
      {[](Camera& c) { c.nearPlane = 0.0; }, "near plane"},
      {[](Camera& c) { c.farPlane = 0.05; }, "far plane"},
      {[](Camera& c) { c.aspectRatio = -1.0; }, "aspect"},
      {[](Camera& c) { c.target = c.position; }, "target"},
      {[](Camera& c) { c.up = c.target - c.position; }, "parallel"},
      {[](Camera& c) { c.position.x = INFINITY; }, "non-finite"},
      {[](Camera& c) { c.projection = Projection::Orthographic, c.farPlane = INFINITY; }, "finite far"},
      {[](Camera& c) { c.projection = Projection::Orthographic, c.farPlane = 9.0, c.xmag = 0.0; }, "xmag"},
      {[](Camera& c) { c.projection = Projection::Orthographic, c.farPlane = 9.0, c.ymag = -1.0; }, "ymag"},
      {[](Camera& c) { c.projection = Projection::Orthographic, c.farPlane = 9.0, c.nearPlane = -1.0; }, "near"},
  };
  for (const Bad& b : bad) {
    Camera c;
    b.edit(c);
    const Status s = validateCamera(c);
    ASSERT_FALSE(s.ok()) << b.says;
    EXPECT_NE(s.error().message.find(b.says), std::string::npos) << s.error().message;
  }
  Camera ortho;
  ortho.projection = Projection::Orthographic;
  ortho.nearPlane = 0.0;  // glTF allows znear 0 for orthographic cameras
  ortho.farPlane = 10.0;
  EXPECT_TRUE(validateCamera(ortho).ok());
}

// A pose from a matrix: scale and shear dropped, -Z the view direction, +Y up; a view matrix likewise.
TEST(CameraMath, PoseFromMatrices) {
  const glm::dmat4 pose = glm::dmat4(glm::dvec4(0, 0, -2, 0), glm::dvec4(0, 3, 0, 0), glm::dvec4(4, 0, 0, 0),
                                     glm::dvec4(1, 2, 3, 1));  // scaled 90-degree turn about +Y
  Camera c;
  ASSERT_TRUE(setCameraPose(c, pose).ok());
  EXPECT_EQ(c.position, glm::dvec3(1, 2, 3));
  EXPECT_NEAR(glm::length(glm::normalize(c.target - c.position) - glm::dvec3(-1, 0, 0)), 0.0, 1e-15);
  EXPECT_NEAR(glm::length(c.up - glm::dvec3(0, 1, 0)), 0.0, 1e-15);
  Camera v;
  ASSERT_TRUE(setCameraView(v, glm::inverse(pose)).ok());
  EXPECT_NEAR(glm::length(v.position - c.position), 0.0, 1e-12);
  EXPECT_FALSE(setCameraPose(c, glm::dmat4(0.0)).ok());
}

class CameraImport : public test::TempDirTest {
 protected:
  // A triangle, a perspective camera (aspectRatio 1.5, zfar 100) on a translated, rotated (-90 degrees about +Y: -Z
  // becomes +X... the node's -Z maps to -X rotated) and scaled node, and an orthographic camera on its child.
  fs::path write(const json& perspective, const json& orthographic) {
    std::vector<uint8_t> bytes(36);
    const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    std::memcpy(bytes.data(), tri, sizeof(tri));
    const double h = std::sqrt(0.5);
    json doc = {
        {"asset", {{"version", "2.0"}}},
        {"buffers", {{{"byteLength", 36}, {"uri", "data:application/octet-stream;base64," + test::base64(bytes)}}}},
        {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}}},
        {"accessors",
         {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"min", {0, 0, 0}},
           {"max", {1, 1, 0}}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
        {"cameras",
         {{{"name", "persp"}, {"type", "perspective"}, {"perspective", perspective}},
          {{"type", "orthographic"}, {"orthographic", orthographic}}}},
        {"nodes",
         {{{"mesh", 0}},
          {{"name", "rig"}, {"camera", 0}, {"translation", {1.0, 2.0, 3.0}}, {"rotation", {0.0, h, 0.0, h}},
           {"scale", {2.0, 2.0, 2.0}}, {"children", {2}}},
          {{"name", "top"}, {"camera", 1}, {"translation", {0.0, 0.0, 5.0}}}}},
        {"scenes", {{{"nodes", {0, 1}}}}},
        {"scene", 0}};
    const fs::path path = dir_ / "cameras.gltf";
    std::ofstream(path) << doc.dump();
    return path;
  }
  static json goodPerspective() { return {{"yfov", 0.7}, {"aspectRatio", 1.5}, {"znear", 0.1}, {"zfar", 100.0}}; }
  static json goodOrthographic() { return {{"xmag", 2.0}, {"ymag", 1.0}, {"znear", 0.0}, {"zfar", 50.0}}; }
};

TEST_F(CameraImport, PerspectiveAndOrthographicNodesWithTheirPose) {
  Result<ImportedScene> s = importGltfScene(write(goodPerspective(), goodOrthographic()).string());
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(s->cameras.size(), 2u);
  const Camera& p = s->cameras[0].camera;
  EXPECT_EQ(s->cameras[0].name, "persp");
  EXPECT_EQ(p.projection, Projection::Perspective);
  EXPECT_EQ(p.fovY, 0.7);
  EXPECT_EQ(p.aspectRatio, 1.5);
  EXPECT_EQ(p.nearPlane, 0.1);
  EXPECT_EQ(p.farPlane, 100.0);
  EXPECT_NEAR(glm::length(p.position - glm::dvec3(1, 2, 3)), 0.0, 1e-12);
  // 90 degrees about +Y: local -Z -> world -X; +Y stays.
  EXPECT_NEAR(glm::length(glm::normalize(p.target - p.position) - glm::dvec3(-1, 0, 0)), 0.0, 1e-7);
  EXPECT_NEAR(glm::length(p.up - glm::dvec3(0, 1, 0)), 0.0, 1e-7);
  const Camera& o = s->cameras[1].camera;
  EXPECT_EQ(s->cameras[1].name, "top");  // unnamed camera: its node's name
  EXPECT_EQ(o.projection, Projection::Orthographic);
  EXPECT_EQ(o.xmag, 2.0);
  EXPECT_EQ(o.ymag, 1.0);
  EXPECT_EQ(o.nearPlane, 0.0);
  EXPECT_EQ(o.farPlane, 50.0);
  // The child's (0, 0, 5) through the parent's scale 2 and turn: (1, 2, 3) + 10 * (+X).
  EXPECT_NEAR(glm::length(o.position - glm::dvec3(11, 2, 3)), 0.0, 1e-6);
  // Built and baked into a pack and back: the cameras stay, as does an orthographic default camera.
  Result<Scene> scene = buildImportedScene(*s);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  ASSERT_EQ(scene->cameras.size(), 2u);
  scene->defaultCamera.projection = Projection::Orthographic;
  scene->defaultCamera.farPlane = 1e4;
  scene->defaultCamera.xmag = 5.0;
  Result<std::vector<uint8_t>> bytes = serializePack(*scene);
  ASSERT_TRUE(bytes.ok()) << bytes.error().message;
  Result<Scene> back = parsePack(bytes->data(), bytes->size(), "pack");
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->cameras, scene->cameras);
  EXPECT_EQ(back->defaultCamera.projection, Projection::Orthographic);
  EXPECT_EQ(back->defaultCamera.xmag, 5.0);
  EXPECT_EQ(back->defaultCamera.farPlane, 1e4);
}

TEST_F(CameraImport, PerspectiveWithoutFarOrAspectIsInfiniteAndViewports) {
  Result<ImportedScene> s = importGltfScene(write({{"yfov", 1.0}, {"znear", 0.5}}, goodOrthographic()).string());
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_TRUE(std::isinf(s->cameras[0].camera.farPlane));
  EXPECT_EQ(s->cameras[0].camera.aspectRatio, 0.0);
}

// Each value glTF forbids is refused, naming the node, the camera and the value.
TEST_F(CameraImport, InvalidCamerasAreRefusedByName) {
  struct Bad {
    json perspective, orthographic;
    const char* says;
  };
  const Bad bad[] = {
      {{{"yfov", 3.2}, {"znear", 0.1}}, goodOrthographic(), "yfov"},
      {{{"yfov", 0.0}, {"znear", 0.1}}, goodOrthographic(), "yfov"},
      {{{"yfov", 1.0}, {"znear", -1.0}}, goodOrthographic(), "znear"},
      {{{"yfov", 1.0}, {"znear", 0.0}}, goodOrthographic(), "znear"},
      {{{"yfov", 1.0}, {"znear", 2.0}, {"zfar", 1.0}}, goodOrthographic(), "zfar"},
      {{{"yfov", 1.0}, {"znear", 0.1}, {"aspectRatio", -2.0}}, goodOrthographic(), "aspectRatio"},
      {goodPerspective(), {{"xmag", 0.0}, {"ymag", 1.0}, {"znear", 0.0}, {"zfar", 5.0}}, "xmag"},
      {goodPerspective(), {{"xmag", 1.0}, {"ymag", -1.0}, {"znear", 0.0}, {"zfar", 5.0}}, "ymag"},
      {goodPerspective(), {{"xmag", 1.0}, {"ymag", 1.0}, {"znear", 5.0}, {"zfar", 5.0}}, "zfar"},
      {goodPerspective(), {{"xmag", 1.0}, {"ymag", 1.0}, {"znear", -1.0}, {"zfar", 5.0}}, "znear"},
  };
  for (const Bad& b : bad) {
    Result<ImportedScene> s = importGltfScene(write(b.perspective, b.orthographic).string());
    ASSERT_FALSE(s.ok()) << b.says;
    EXPECT_NE(s.error().message.find(b.says), std::string::npos) << s.error().message;
    EXPECT_NE(s.error().message.find("camera"), std::string::npos) << s.error().message;
  }
}

// Whether every point is inside the default camera's view (square viewport: the framing's vertical field).
void expectFramed(const Scene& scene, const std::vector<glm::dvec4>& spheres, const std::string& what) {
  const FrameMath fm = computeFrameMath(scene.defaultCamera, 64, 64);
  for (const glm::dvec4& s : spheres)
    EXPECT_LE(sphereFrustumDistance(fm, scene.defaultCamera, glm::dvec3(s), -s.w), 0.0)
        << what << ": (" << s.x << ", " << s.y << ", " << s.z << ") r " << s.w << " leaves the frame";
}

// Every animated object's vertices (skinned / morphed on the CPU) or bounding sphere (rigid) at times that are not
// the framing's samples, over every clip.
std::vector<glm::dvec4> animatedParts(const Scene& scene) {
  std::vector<glm::dvec4> out;
  for (size_t clip = 0; clip < scene.animations.size(); ++clip) {
    const double duration = scene.animations[clip].duration;
    for (double u : {0.013, 0.29, 0.517, 0.731, 0.977}) {
      const double t = u * duration;
      for (RigidObject ro : scene.rigidObjects) {
        ro.clip = int32_t(clip);
        const glm::dmat4 m = rigidObjectTransform(scene, ro, t);
        const Mesh& mesh = scene.meshes[scene.objects[ro.object].mesh];
        for (const gpu::Vertex& v : mesh.vertices) out.push_back({glm::dvec3(m * glm::dvec4(v.px, v.py, v.pz, 1)), 0});
      }
      for (SkinnedObject so : scene.skinnedObjects) {
        so.clip = int32_t(clip);
        const Mesh& mesh = scene.meshes[scene.objects[so.object].mesh];
        const auto joints = skinnedObjectJoints(scene, so, t);
        const auto weights = skinnedObjectMorphWeights(scene, so, t);
        for (uint32_t v = 0; v < mesh.vertices.size(); v += 7)
          out.push_back(
              {glm::dvec3(so.placement * glm::dvec4(skinPosition(morphVertex(mesh, v, weights).position,
                                                                  mesh.skinVertices[v], joints), 1.0)), 0.0});
      }
    }
  }
  return out;
}

class AnimatedFraming : public test::TempDirTest {};

// A triangle that a clip moves 20 units along +X (the rest pose at the origin): the default camera frames the whole
// path; a camera framing the rest pose alone (the bounds without animation) loses it.
TEST_F(AnimatedFraming, NodeAnimationLeavingTheRestPoseStaysInFrame) {
  std::vector<float> data = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.0f, 1.0f, 0, 0, 0, 20, 0, 0};
  std::vector<uint8_t> bytes(data.size() * 4);
  std::memcpy(bytes.data(), data.data(), bytes.size());
  json doc = {
      {"asset", {{"version", "2.0"}}},
      {"buffers", {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(bytes)}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 8}},
        {{"buffer", 0}, {"byteOffset", 44}, {"byteLength", 24}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"min", {0, 0, 0}},
         {"max", {1, 1, 0}}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}, {"min", {0.0}}, {"max", {1.0}}},
        {{"bufferView", 2}, {"componentType", 5126}, {"count", 2}, {"type", "VEC3"}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
      {"nodes", {{{"mesh", 0}}, {{"mesh", 0}, {"translation", {0, -1, 0}}}}},
      {"animations",
       {{{"samplers", {{{"input", 1}, {"output", 2}}}},
         {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "translation"}}}}}}}}},
      {"scenes", {{{"nodes", {0, 1}}}}},
      {"scene", 0}};
  const fs::path path = dir_ / "moving.gltf";
  std::ofstream(path) << doc.dump();
  Result<ImportedScene> imported = importGltfScene(path.string());
  ASSERT_TRUE(imported.ok()) << imported.error().message;
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  ASSERT_EQ(scene->rigidObjects.size(), 1u);
  const std::vector<glm::dvec4> parts = animatedParts(*scene);
  ASSERT_FALSE(parts.empty());
  expectFramed(*scene, parts, "moving triangle");
  Scene restFramed = *scene;
  restFramed.rigidObjects.clear();  // what the rest pose alone spans
  frameScene(restFramed);
  const FrameMath fm = computeFrameMath(restFramed.defaultCamera, 64, 64);
  size_t lost = 0;
  for (const glm::dvec4& p : parts) lost += !sphereInFrustum(fm, restFramed.defaultCamera, glm::dvec3(p), 0.0);
  EXPECT_GT(lost, 0u);
}

// The repository's animated assets: skinned (CesiumMan, Fox with three clips), morphed (AnimatedMorphCube) and
// node-animated (CesiumMilkTruck): every animated part stays in the default camera's frame at times between the
// framing's samples, over every clip.
TEST(AnimatedFramingAssets, EveryAnimatedPartStaysInFrame) {
  for (const char* asset : {"CesiumMan/glTF/CesiumMan.gltf", "Fox/glTF-Binary/Fox.glb",
                            "AnimatedMorphCube/glTF/AnimatedMorphCube.gltf",
                            "CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb"}) {
    const fs::path path = test::repoAssetsDir() / asset;
    ASSERT_TRUE(fs::exists(path)) << path;
    Result<ImportedScene> imported = importGltfScene(path.string());
    ASSERT_TRUE(imported.ok()) << asset << ": " << imported.error().message;
    Result<Scene> scene = buildImportedScene(*imported);
    ASSERT_TRUE(scene.ok()) << asset << ": " << scene.error().message;
    const std::vector<glm::dvec4> parts = animatedParts(*scene);
    EXPECT_FALSE(parts.empty()) << asset;
    expectFramed(*scene, parts, asset);
  }
}

}  // namespace
}  // namespace visbuf
