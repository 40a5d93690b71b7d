// loadScene (engine/asset/load_scene.h): a glTF loaded directly equals the pack baked from it (the reference:
// the bake's own steps, written and read back), copies of either, the lights each copy carries, and the errors.
#include <glm/gtc/matrix_transform.hpp>

#include "../build_config.h"
#include "pack_test_util.h"
#include "visbuf/asset/load_scene.h"
#include "visbuf/asset/texture_bake.h"

namespace visbuf {
namespace {

using pack_test::expectScenesEqual;
namespace fs = std::filesystem;

class LoadSceneTest : public test::TempDirTest {
 protected:
  // What `visbuf bake FILE -o PACK` does with its default options: import, build, bake the textures, write.
  fs::path bakePack(const fs::path& gltf) {
    Result<ImportedScene> imported = importGltfScene(gltf.string());
    EXPECT_TRUE(imported) << imported.error().message;
    if (!imported) return {};
    Result<Scene> scene = buildImportedScene(*imported);
    EXPECT_TRUE(scene) << scene.error().message;
    if (!scene) return {};
    Status t = bakeTextures(*imported, TextureBakeOptions{}, &scene.value());
    EXPECT_TRUE(t) << t.error().message;
    scene->name = gltf.string();  // (loadScene names a glTF's scene after its path; the pack keeps the name)
    const fs::path pack = dir_ / (gltf.stem().string() + ".vbp");
    Status w = writePack(*scene, pack.string());
    EXPECT_TRUE(w) << w.error().message;
    return pack;
  }
};

// The white-fox class of bug: a glTF rendered directly must carry the textures its pack carries. Fox (a skinned
// mesh, one base colour texture) and CesiumMilkTruck (node-animated wheels, two materials textured).
TEST_F(LoadSceneTest, GltfEqualsThePackBakedFromIt) {
  SKIP_WITHOUT_OIIO();
  for (const char* relative : {"Fox/glTF-Binary/Fox.glb", "CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb"}) {
    const fs::path gltf = test::assetPath(relative);
    SCOPED_TRACE(gltf.string());
    REQUIRE_ASSET(gltf);
    const fs::path pack = bakePack(gltf);
    ASSERT_FALSE(pack.empty());
    for (uint32_t instances : {1u, 3u}) {
      SCOPED_TRACE(instances);
      LoadOptions options;
      options.instances = instances;
      Result<LoadedScene> direct = loadScene(gltf, options);
      ASSERT_TRUE(direct) << direct.error().message;
      Result<LoadedScene> baked = loadScene(pack, options);
      ASSERT_TRUE(baked) << baked.error().message;
      EXPECT_EQ(direct->kind, SceneFileKind::Gltf);
      EXPECT_EQ(baked->kind, SceneFileKind::Pack);
      EXPECT_TRUE(baked->warnings.empty());
      expectScenesEqual(direct->scene, baked->scene);
      EXPECT_EQ(direct->scene.pointLights.size(), baked->scene.pointLights.size());
      // Textured: every material that names a base colour image has it baked.
      ASSERT_FALSE(direct->scene.textures.empty());
      size_t textured = 0;
      for (const Material& m : direct->scene.materials)
        if (m.baseColorTexture.image >= 0) {
          EXPECT_GE(m.baseColorTexture.baked, 0) << m.name;
          ++textured;
        }
      EXPECT_GE(textured, 1u);
    }
  }
}

TEST_F(LoadSceneTest, CopiesAndObjectOrder) {
  const fs::path gltf = test::assetPath("CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb");
  REQUIRE_ASSET(gltf);
  LoadOptions options;
  options.objectOrder = ObjectOrder::AsBuilt;
  Result<LoadedScene> one = loadScene(gltf, options);
  ASSERT_TRUE(one) << one.error().message;
  options.instances = 4;
  Result<LoadedScene> four = loadScene(gltf, options);
  ASSERT_TRUE(four) << four.error().message;
  ASSERT_EQ(four->scene.objects.size(), 4 * one->scene.objects.size());
  EXPECT_EQ(four->scene.rigidObjects.size(), 4 * one->scene.rigidObjects.size());
  EXPECT_EQ(four->scene.meshes.size(), one->scene.meshes.size());  // shared, not copied
  EXPECT_EQ(four->scene.textures.size(), one->scene.textures.size());
  // As built: copy k's objects are objects [k n, (k + 1) n), in the file's order.
  const size_t n = one->scene.objects.size();
  for (size_t k = 0; k < 4; ++k)
    for (size_t i = 0; i < n; ++i) EXPECT_EQ(four->scene.objects[k * n + i].mesh, one->scene.objects[i].mesh);
  // Spatial order: the same objects, renumbered.
  options.objectOrder = ObjectOrder::Spatial;
  Result<LoadedScene> spatial = loadScene(gltf, options);
  ASSERT_TRUE(spatial) << spatial.error().message;
  ASSERT_EQ(spatial->scene.objects.size(), four->scene.objects.size());
  std::vector<uint32_t> meshesA, meshesB;
  for (const Object& o : four->scene.objects) meshesA.push_back(o.mesh);
  for (const Object& o : spatial->scene.objects) meshesB.push_back(o.mesh);
  std::sort(meshesA.begin(), meshesA.end());
  std::sort(meshesB.begin(), meshesB.end());
  EXPECT_EQ(meshesA, meshesB);
}

TEST_F(LoadSceneTest, RefusesBadOptionsAndNamesBadFiles) {
  const fs::path gltf = test::assetPath("Fox/glTF-Binary/Fox.glb");
  LoadOptions zero;
  zero.instances = 0;
  Result<LoadedScene> r = loadScene(gltf, zero);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument);
  LoadOptions size;
  size.maxTextureSize = 3;
  r = loadScene(gltf, size);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(r.error().message.find("maxTextureSize 3"), std::string::npos) << r.error().message;

  // Copies past maxObjects are refused before any is made (Fox: 1 object a copy).
  LoadOptions many;
  many.instances = 11;
  many.maxObjects = 10;
  r = loadScene(gltf, many);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::CapacityExceeded);
  EXPECT_NE(r.error().message.find("11 copies of 1 objects make 11 objects, over the 10 allowed"), std::string::npos)
      << r.error().message;
  EXPECT_NE(r.error().message.find("Fox.glb"), std::string::npos) << r.error().message;
  // 2^32 - 1 copies fit 32-bit object indices, not the import memory budget (4 GiB by default); 5 x 10^9 objects
  // fit neither (the index bound holds whatever the budget).
  many.instances = 4294967295u;
  many.maxObjects = UINT64_MAX;
  r = loadScene(gltf, many);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::CapacityExceeded);
  EXPECT_NE(r.error().message.find("maxImportMemory"), std::string::npos) << r.error().message;
  many.instances = 1000000000u;
  many.maxImportMemory = uint64_t{1} << 60;
  r = loadScene(test::assetPath("CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb"), many);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::CapacityExceeded);
  EXPECT_NE(r.error().message.find("over the 4294967295 allowed"), std::string::npos) << r.error().message;

  r = loadScene(dir_ / "missing.glb");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::FileNotFound) << r.error().message;
  // A damaged file named .vbp is read as a pack (the pack reader's message, not the glTF parser's).
  const fs::path junk = dir_ / "junk.vbp";
  std::ofstream(junk) << "not a pack at all, but long enough to have a header's worth of bytes in it........";
  EXPECT_EQ(sceneFileKind(junk), SceneFileKind::Pack);
  r = loadScene(junk);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("junk.vbp"), std::string::npos) << r.error().message;
  // A pack is told by its magic whatever its name.
  const Scene scene = pack_test::makeTestScene(16, 6);
  const fs::path disguised = dir_ / "pack.glb";
  ASSERT_TRUE(writePack(scene, disguised.string()));
  EXPECT_EQ(sceneFileKind(disguised), SceneFileKind::Pack);
  EXPECT_EQ(sceneFileKind(gltf), SceneFileKind::Gltf);
  Result<LoadedScene> loaded = loadScene(disguised);
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(loaded->scene.objects.size(), scene.objects.size());
}

// Copies carry the asset's lights: point and spot lights placed, ranged and scaled with each copy (checked
// against the copy's own object placement), directional lights once.
TEST(AnimatedFieldLights, EveryCopyCarriesItsPointAndSpotLights) {
  Scene asset = pack_test::makeTestScene(16, 6);
  asset.skinnedObjects.clear();
  asset.rigidObjects.clear();
  asset.objects.resize(1);
  asset.objects[0].transform = glm::translate(glm::dmat4(1.0), glm::dvec3(5.0, 1.0, -2.0));
  PointLight point;
  point.position = {6.0, 2.0, -2.0};
  point.range = 4.0f;
  point.intensity = 8.0f;
  PointLight spot = point;
  spot.type = LightType::Spot;
  spot.direction = {0.0f, -1.0f, 0.0f};
  spot.range = 0.0f;  // infinite: stays infinite
  PointLight sun;
  sun.type = LightType::Directional;
  sun.direction = glm::normalize(glm::vec3(1.0f, -1.0f, 0.0f));
  sun.intensity = 3.0f;
  asset.pointLights = {point, spot, sun};
  AnimatedFieldParams p;
  p.instances = 4;
  Result<Scene> field = makeAnimatedField(asset, p);
  ASSERT_TRUE(field) << field.error().message;
  ASSERT_EQ(field->objects.size(), 4u);
  ASSERT_EQ(field->pointLights.size(), 4u * 2 + 1);
  size_t directional = 0, k = 0;
  for (const PointLight& l : field->pointLights) {
    if (l.type == LightType::Directional) {
      ++directional;
      EXPECT_EQ(l.direction, sun.direction);
      EXPECT_EQ(l.intensity, sun.intensity);
      continue;
    }
    // The copy's placement, from its object: object transform = placement x the asset's.
    const size_t copy = k++ / 2;
    const glm::dmat4 place = field->objects[copy].transform * glm::inverse(asset.objects[0].transform);
    const double scale = std::cbrt(glm::determinant(glm::dmat3(place)));
    const PointLight& source = l.type == LightType::Point ? point : spot;
    const glm::dvec3 expected = glm::dvec3(place * glm::dvec4(source.position, 1.0));
    EXPECT_LT(glm::length(l.position - expected), 1e-9 * (1.0 + glm::length(expected)));
    EXPECT_NEAR(l.intensity, source.intensity * scale * scale, 1e-5 * source.intensity * scale * scale);
    if (l.type == LightType::Point) {
      EXPECT_NEAR(l.range, source.range * scale, 1e-5 * source.range * scale);
    } else {
      EXPECT_EQ(l.range, 0.0f);
      const glm::dvec3 d = glm::normalize(glm::dmat3(place) * glm::dvec3(spot.direction));
      EXPECT_LT(glm::length(glm::dvec3(l.direction) - d), 1e-6);
    }
  }
  EXPECT_EQ(directional, 1u);
}

}  // namespace
}  // namespace visbuf
