// Rigid node animation (scene.h RigidObject, rigidObjectTransform): an unskinned mesh node moved by a translation /
// rotation / scale channel on itself or an ancestor is a plain object whose transform follows the clip. Checked
// against transforms built by hand from the keyframes, on CesiumMilkTruck's wheels, and through a pack.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "temp_dir_test.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/generate.h"
#include "visbuf/scene/scene.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

double maxDifference(const glm::dmat4& a, const glm::dmat4& b) {
  double d = 0.0;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) d = std::max(d, std::abs(a[c][r] - b[c][r]));
  return d;
}

// A file with one animated parent node (translation (1, 2, 3), scale 2, a LINEAR rotation channel from identity
// at t = 0 to 90 degrees about +Y at t = 2) and a child mesh node with a static translation (0.5, 0, 0).
class RigidGltf : public test::TempDirTest {
 protected:
  // The rotation keys as the file stores them (float), x y z w.
  static constexpr float kKey1[4] = {0.0f, 0.70710677f, 0.0f, 0.70710677f};

  fs::path write() {
    std::vector<float> data = {0, 0, 0, 1, 0, 0, 0, 1, 0,       // positions
                               0, 0, 1, 0, 0, 1, 0, 0, 1,       // normals
                               0.0f, 2.0f,                      // key times
                               0, 0, 0, 1, kKey1[0], kKey1[1], kKey1[2], kKey1[3]};  // rotations
    const fs::path bin = dir_ / "rigid.bin";
    std::ofstream(bin, std::ios::binary)
        .write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size() * sizeof(float)));
    json doc = {
        {"asset", {{"version", "2.0"}}},
        {"buffers", {{{"byteLength", data.size() * 4}, {"uri", "rigid.bin"}}}},
        {"bufferViews",
         {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
          {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 36}},
          {{"buffer", 0}, {"byteOffset", 72}, {"byteLength", 8}},
          {{"buffer", 0}, {"byteOffset", 80}, {"byteLength", 32}}}},
        {"accessors",
         {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"min", {0, 0, 0}},
           {"max", {1, 1, 0}}},
          {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
          {{"bufferView", 2}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}, {"min", {0.0}},
           {"max", {2.0}}},
          {{"bufferView", 3}, {"componentType", 5126}, {"count", 2}, {"type", "VEC4"}}}},
        {"meshes", {{{"name", "tri"}, {"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}}}}}}},
        {"nodes",
         {{{"name", "spinner"}, {"children", {1}}, {"translation", {1, 2, 3}}, {"scale", {2, 2, 2}}},
          {{"name", "arm"}, {"mesh", 0}, {"translation", {0.5, 0, 0}}}}},
        {"animations",
         {{{"name", "spin"},
           {"samplers", {{{"input", 2}, {"output", 3}, {"interpolation", "LINEAR"}}}},
           {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "rotation"}}}}}}}}},
        {"scenes", {{{"nodes", {0}}}}},
        {"scene", 0}};
    const fs::path path = dir_ / "rigid.gltf";
    std::ofstream(path) << doc.dump();
    return path;
  }

  // The child's world matrix at time t, built from the keyframes: glTF LINEAR rotation is the spherical
  // interpolation of the (normalised) keys at (t mod 2) / 2.
  static glm::dmat4 expected(double t) {
    const double u = std::fmod(t, 2.0) / 2.0;
    const glm::dquat q0(1.0, 0.0, 0.0, 0.0);
    const glm::dquat q1 = glm::normalize(glm::dquat(kKey1[3], kKey1[0], kKey1[1], kKey1[2]));
    const glm::dquat q = glm::slerp(q0, q1, u);
    const glm::dmat4 parent = glm::translate(glm::dmat4(1.0), glm::dvec3(1, 2, 3)) * glm::mat4_cast(q) *
                              glm::scale(glm::dmat4(1.0), glm::dvec3(2.0));
    const glm::dmat4 child = glm::translate(glm::dmat4(1.0), glm::dvec3(0.5, 0, 0));
    return parent * child;
  }
};

TEST_F(RigidGltf, ChildOfAnimatedNodeFollowsTheKeyframes) {
  const fs::path path = write();
  Result<ImportedScene> imported = importGltfScene(path.string());
  ASSERT_TRUE(imported) << imported.error().message;
  ASSERT_EQ(imported->instances.size(), 1u);
  EXPECT_TRUE(imported->instances[0].rigid);
  EXPECT_EQ(imported->instances[0].skin, -1);
  EXPECT_TRUE(imported->skins.empty());
  ASSERT_EQ(imported->nodes.size(), 2u);
  ASSERT_EQ(imported->animations.size(), 1u);

  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene) << scene.error().message;
  EXPECT_TRUE(validateScene(*scene));
  EXPECT_TRUE(scene->skinnedObjects.empty());
  ASSERT_EQ(scene->rigidObjects.size(), 1u);
  const RigidObject& ro = scene->rigidObjects[0];
  EXPECT_EQ(ro, (RigidObject{0, 1, 0, 0.0, glm::dmat4(1.0)}));

  // Object::transform is the time-0 pose.
  EXPECT_EQ(scene->objects[0].transform, rigidObjectTransform(*scene, ro, 0.0));
  EXPECT_LT(maxDifference(scene->objects[0].transform, expected(0.0)), 1e-14);
  for (double t : {0.5, 1.5, 2.5}) {
    const glm::dmat4 got = rigidObjectTransform(*scene, ro, t);
    EXPECT_LT(maxDifference(got, expected(t)), 1e-14) << "t = " << t;
    EXPECT_EQ(rigidObjectTransforms(*scene, t)[0], got) << "t = " << t;
  }
  EXPECT_GT(maxDifference(rigidObjectTransform(*scene, ro, 0.5), rigidObjectTransform(*scene, ro, 1.5)), 0.1);

  // Placement and time offset: placement * (the transform at t + offset).
  RigidObject copy = ro;
  copy.placement = glm::translate(glm::dmat4(1.0), glm::dvec3(100.0, 0.0, -50.0));
  copy.timeOffset = 0.75;
  EXPECT_LT(maxDifference(rigidObjectTransform(*scene, copy, 0.5), copy.placement * expected(1.25)), 1e-12);
}

// A clip that starts at scale 0: the time-0 pose is singular, so the object keeps its rest-pose transform.
TEST_F(RigidGltf, SingularStartPoseKeepsTheRestTransform) {
  Result<ImportedScene> imported = importGltfScene(write().string());
  ASSERT_TRUE(imported) << imported.error().message;
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene) << scene.error().message;
  AnimationClip& clip = scene->animations[0];
  clip.samplers.push_back({Interpolation::Linear, 3, {0.0f, 2.0f}, {0, 0, 0, 1, 1, 1}});
  clip.channels.push_back({1, 0, AnimationPath::Scale});
  ASSERT_TRUE(validateScene(*scene));
  const RigidObject& ro = scene->rigidObjects[0];
  const glm::dmat4 rest = imported->instances[0].transform;
  EXPECT_EQ(glm::determinant(glm::dmat3(rigidObjectTransform(*scene, ro, 0.0))), 0.0);
  EXPECT_EQ(rigidObjectStartTransform(*scene, ro, rest), rest);
  RigidObject later = ro;
  later.timeOffset = 1.0;
  EXPECT_EQ(rigidObjectStartTransform(*scene, later, rest), rigidObjectTransform(*scene, later, 0.0));
}

TEST_F(RigidGltf, ValidationNamesBadReferences) {
  Result<ImportedScene> imported = importGltfScene(write().string());
  ASSERT_TRUE(imported) << imported.error().message;
  Result<Scene> built = buildImportedScene(*imported);
  ASSERT_TRUE(built);
  auto refused = [&](auto edit, const std::string& text) {
    Scene s = *built;
    edit(s.rigidObjects[0]);
    const Status st = validateScene(s);
    if (st) return ::testing::AssertionFailure() << "accepted; expected '" << text << "'";
    if (st.error().message.find(text) == std::string::npos)
      return ::testing::AssertionFailure() << "message '" << st.error().message << "' lacks '" << text << "'";
    return ::testing::AssertionSuccess();
  };
  EXPECT_TRUE(refused([](RigidObject& r) { r.object = 5; }, "rigid object 0: object 5 out of range (1 objects)"));
  EXPECT_TRUE(refused([](RigidObject& r) { r.node = 2; }, "rigid object 0: node 2 out of range (2 nodes)"));
  EXPECT_TRUE(refused([](RigidObject& r) { r.node = -1; }, "rigid object 0: node -1 out of range"));
  EXPECT_TRUE(refused([](RigidObject& r) { r.clip = 1; }, "rigid object 0: clip 1 is not -1 or an animation index"));
  EXPECT_TRUE(refused([](RigidObject& r) { r.timeOffset = NAN; }, "rigid object 0: time offset nan is not finite"));
  EXPECT_TRUE(refused([](RigidObject& r) { r.placement[0][3] = 1.0; }, "placement is not a finite affine matrix"));
  Scene twice = *built;
  twice.rigidObjects.push_back(twice.rigidObjects[0]);
  ASSERT_FALSE(validateScene(twice));
  EXPECT_NE(validateScene(twice).error().message.find("rigid object 1: object 0 is listed twice"), std::string::npos);
}

Result<Scene> bakedTruck() {
  const fs::path path = test::repoAssetsDir() / "CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb";
  Result<ImportedScene> imported = importGltfScene(path.string());
  if (!imported) return imported.error();
  return buildImportedScene(*imported);
}

// CesiumMilkTruck: the two wheel nodes ("Wheels", "Wheels.001") have rotation channels; the body does not move.
TEST(RigidAnimation, CesiumMilkTruckWheelsTurnAndTheBodyStays) {
  Result<Scene> scene = bakedTruck();
  ASSERT_TRUE(scene) << scene.error().message;
  EXPECT_TRUE(scene->skinnedObjects.empty());
  EXPECT_TRUE(scene->skins.empty());
  ASSERT_EQ(scene->rigidObjects.size(), 2u);
  std::vector<uint8_t> rigid(scene->objects.size(), 0);
  for (const RigidObject& ro : scene->rigidObjects) {
    rigid[ro.object] = 1;
    ASSERT_GE(ro.node, 0);
    const std::string& name = scene->nodes[size_t(ro.node)].name;
    EXPECT_EQ(name.rfind("Wheels", 0), 0u) << name;
    EXPECT_EQ(ro.clip, 0);
    EXPECT_EQ(scene->objects[ro.object].transform, rigidObjectTransform(*scene, ro, 0.0));
    const glm::dmat4 a = rigidObjectTransform(*scene, ro, 0.0), b = rigidObjectTransform(*scene, ro, 0.5);
    EXPECT_GT(maxDifference(a, b), 1e-3) << name << ": the wheel does not turn";
    // A wheel turns about its axle: its origin stays put.
    EXPECT_LT(glm::length(glm::dvec3(a[3]) - glm::dvec3(b[3])), 1e-9) << name;
  }
  size_t still = 0;
  for (size_t o = 0; o < scene->objects.size(); ++o) {
    if (rigid[o]) continue;
    ++still;
    EXPECT_NE(scene->meshes[scene->objects[o].mesh].name.find("Cesium_Milk_Truck"), std::string::npos)
        << scene->meshes[scene->objects[o].mesh].name;
  }
  EXPECT_GE(still, 1u);  // the body (one object per material)
  const int32_t body = 4;  // node 'Cesium_Milk_Truck'
  ASSERT_EQ(scene->nodes[body].name, "Cesium_Milk_Truck");
  EXPECT_EQ(firstClipMoving(*scene, body), -1);
}

TEST(RigidAnimation, PackRoundTripKeepsRigidObjects) {
  Result<Scene> scene = bakedTruck();
  ASSERT_TRUE(scene) << scene.error().message;
  // A second phase and a placement, as --instances writes them.
  scene->rigidObjects[1].timeOffset = 0.375;
  scene->rigidObjects[1].clip = -1;
  scene->rigidObjects[0].placement = glm::translate(glm::dmat4(1.0), glm::dvec3(-7.5, 0.25, 1e5));
  Result<std::vector<uint8_t>> bytes = serializePack(*scene);
  ASSERT_TRUE(bytes) << bytes.error().message;
  Result<Scene> back = parsePack(bytes->data(), bytes->size(), "truck.vbp");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->rigidObjects, scene->rigidObjects);
  EXPECT_TRUE(back->nodes == scene->nodes);
  EXPECT_TRUE(back->animations == scene->animations);
  ASSERT_EQ(back->objects.size(), scene->objects.size());
  for (size_t o = 0; o < scene->objects.size(); ++o) EXPECT_EQ(back->objects[o].transform, scene->objects[o].transform);
  for (size_t i = 0; i < scene->rigidObjects.size(); ++i)
    EXPECT_EQ(rigidObjectTransform(*back, back->rigidObjects[i], 1.25),
              rigidObjectTransform(*scene, scene->rigidObjects[i], 1.25));
}

// --instances N (makeAnimatedField): every copy's rigid objects have their own placement and phase, and their
// objects hold that pose at time 0.
TEST(RigidAnimation, CopiesOfTheTruckTurnTheirWheelsAtTheirOwnPhase) {
  Result<Scene> truck = bakedTruck();
  ASSERT_TRUE(truck) << truck.error().message;
  Result<Scene> field = makeAnimatedField(*truck, {.instances = 3, .seed = 9, .spacing = 2.0});
  ASSERT_TRUE(field) << field.error().message;
  EXPECT_TRUE(validateScene(*field));
  ASSERT_EQ(field->objects.size(), 3 * truck->objects.size());
  ASSERT_EQ(field->rigidObjects.size(), 3 * truck->rigidObjects.size());
  EXPECT_TRUE(field->skinnedObjects.empty());
  const double duration = truck->animations[0].duration;
  for (size_t i = 0; i < field->rigidObjects.size(); ++i) {
    const RigidObject& ro = field->rigidObjects[i];
    const RigidObject& source = truck->rigidObjects[i % truck->rigidObjects.size()];
    const size_t copy = i / truck->rigidObjects.size();
    EXPECT_EQ(ro.object, copy * truck->objects.size() + source.object);
    EXPECT_EQ(ro.node, source.node);
    EXPECT_GE(ro.timeOffset, 0.0);
    EXPECT_LT(ro.timeOffset, duration);
    EXPECT_EQ(field->objects[ro.object].transform, rigidObjectTransform(*field, ro, 0.0));
    // The copy's placement times the file's pose at the copy's phase.
    const glm::dmat4 place = ro.placement;
    RigidObject atPhase = source;
    atPhase.timeOffset = ro.timeOffset;
    EXPECT_LT(maxDifference(rigidObjectTransform(*field, ro, 0.3), place * rigidObjectTransform(*truck, atPhase, 0.3)),
              1e-12);
  }
  EXPECT_NE(field->rigidObjects[0].timeOffset, field->rigidObjects[2].timeOffset);
  EXPECT_NE(field->rigidObjects[0].placement, field->rigidObjects[2].placement);
}

}  // namespace
}  // namespace visbuf
