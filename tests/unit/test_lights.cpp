// Lights on the CPU: the BRDF reference against closed-form values of the glTF 2.0 appendix B formulas,
// point light validation and scattering, KHR_lights_punctual import.
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "visbuf/asset/gltf_import.h"
#include "visbuf/render/brdf_reference.h"
#include "visbuf/scene/generate.h"
#include "visbuf/scene/light.h"
#include "temp_dir_test.h"
#include "test_assets.h"

using namespace visbuf;

// Normal incidence (n = v = l, h = n): F = f0, D = a^2 / (pi a^4) = 1 / (pi a^2) with a = roughness^2, and the
// height-correlated Smith term V = 0.5 / (1 sqrt(1 (1 - a^2) + a^2) + 1 sqrt(...)) = 0.25 for every roughness.
TEST(LightsCpu, BrdfReferenceAtNormalIncidence) {
  SurfaceReference s;
  s.normal = {0, 0, 1};
  const glm::dvec3 n{0, 0, 1};
  for (double roughness : {0.3, 0.7, 1.0}) {
    for (double metallic : {0.0, 1.0}) {
      s.roughness = roughness;
      s.metallic = metallic;
      s.baseColor = {0.8, 0.5, 0.2};
      const double a2 = std::pow(roughness, 4.0);
      for (int c = 0; c < 3; ++c) {
        const double f0 = metallic > 0 ? s.baseColor[c] : 0.04;
        const double diffuse = (1.0 - f0) * (metallic > 0 ? 0.0 : s.baseColor[c]) / std::numbers::pi;
        const double expected = diffuse + f0 * (1.0 / (std::numbers::pi * a2)) * 0.25;
        EXPECT_NEAR(brdfCosineReference(s, n, n)[c], expected, 1e-12 * expected)
            << "roughness " << roughness << " metallic " << metallic;
      }
    }
  }
  // Light below the horizon: nothing.
  EXPECT_EQ(brdfCosineReference(s, n, glm::normalize(glm::dvec3(1, 0, -0.1))), glm::dvec3(0.0));
}

// A point light: inverse square inside the range, the (1 - (d/r)^4)^2 window, exactly zero beyond it.
TEST(LightsCpu, PointLightFalloffAndRange) {
  Scene scene;
  scene.lightIntensity = 0.0f;
  PointLight l;
  l.position = {0, 0, 0};
  l.intensity = 4.0f;
  l.range = 10.0f;
  scene.pointLights.push_back(l);
  SurfaceReference s;
  s.normal = {0, 0, 1};
  s.baseColor = {1, 1, 1};
  const glm::dvec3 camera{0, 0, 100};
  auto direct = [&](double d) {  // surface d below the light, facing it, seen from straight above
    s.position = glm::dvec3(0, 0, -d) - camera;
    return shadeReference(s, scene, camera)[0] - AMBIENT_RADIANCE * (1.0 + 0.04);
  };
  const glm::dvec3 n{0, 0, 1};
  s.position = glm::dvec3(0, 0, -2) - camera;
  const double brdf = brdfCosineReference(s, n, n)[0];
  const double w = std::pow(1.0 - std::pow(2.0 / 10.0, 4.0), 2.0);
  EXPECT_NEAR(direct(2.0), brdf * 4.0 * w / 4.0, 1e-12);
  EXPECT_EQ(direct(10.0), 0.0);
  EXPECT_EQ(direct(12.0), 0.0);
}

TEST(LightsCpu, ValidateRejectsBadLights) {
  PointLight ok;
  EXPECT_TRUE(validatePointLights({ok}).ok());
  PointLight nan = ok;
  nan.position.y = std::nan("");
  EXPECT_FALSE(validatePointLights({ok, nan}).ok());
  EXPECT_NE(validatePointLights({ok, nan}).error().message.find("point light 1"), std::string::npos);
  PointLight negative = ok;
  negative.intensity = -1.0f;
  EXPECT_FALSE(validatePointLights({negative}).ok());
}

TEST(LightsCpu, ScatterFillsTheSceneBounds) {
  FieldParams p;
  p.objects = 50;
  p.extent = 20.0;
  Scene scene = makeFieldScene(p).value();
  scatterPointLights(scene, 0, 1);
  EXPECT_TRUE(scene.pointLights.empty());
  scatterPointLights(scene, 500, 1);
  ASSERT_EQ(scene.pointLights.size(), 500u);
  for (const PointLight& l : scene.pointLights) {
    EXPECT_LE(glm::length(l.position), std::sqrt(3.0) * (20.0 + 4.0 * 1.0001));  // inside the bounds' box
    EXPECT_GT(l.range, 0.0f);
    EXPECT_NEAR(l.intensity, 0.5f * l.range * l.range, 1e-3f * l.intensity);
  }
  EXPECT_TRUE(validateScene(scene).ok());
}

class LightImportTest : public test::TempDirTest {};

// A triangle at the origin and a point light on a translated, scaled node: position from the node's world
// transform, range and intensity as written; a spot light is skipped with a warning.
TEST_F(LightImportTest, KhrLightsPunctualPointLights) {
  std::vector<uint8_t> bytes(36);
  const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(bytes.data(), tri, sizeof(tri));
  nlohmann::json doc = {
      {"asset", {{"version", "2.0"}}},
      {"extensionsUsed", {"KHR_lights_punctual"}},
      {"extensions",
       {{"KHR_lights_punctual",
         {{"lights",
           {{{"type", "point"}, {"color", {1.0, 0.5, 0.25}}, {"intensity", 7.0}, {"range", 12.0}},
            {{"type", "spot"}, {"spot", {{"outerConeAngle", 0.5}}}}}}}}}},
      {"buffers", {{{"byteLength", 36}, {"uri", "data:application/octet-stream;base64," + test::base64(bytes)}}}},
      {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"min", {0, 0, 0}},
         {"max", {1, 1, 0}}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
      {"nodes",
       {{{"mesh", 0}},
        {{"translation", {1.0, 2.0, 3.0}}, {"children", {2, 3}}},
        {{"translation", {0.0, 0.0, 5.0}}, {"scale", {2.0, 2.0, 2.0}},
         {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}},
        {{"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}}}},
      {"scenes", {{{"nodes", {0, 1}}}}},
      {"scene", 0}};
  const std::string path = (dir_ / "light.gltf").string();
  std::ofstream(path) << doc.dump();
  GltfImportReport report;
  Result<ImportedScene> s = importGltfScene(path, {}, &report);
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(s->pointLights.size(), 1u);
  const PointLight& l = s->pointLights[0];
  EXPECT_EQ(l.position, glm::dvec3(1.0, 2.0, 8.0));
  EXPECT_EQ(l.color, glm::vec3(1.0f, 0.5f, 0.25f));
  EXPECT_EQ(l.intensity, 7.0f);
  EXPECT_EQ(l.range, 12.0f);
  bool warned = false;
  for (const std::string& w : report.warnings) warned = warned || w.find("spot") != std::string::npos;
  EXPECT_TRUE(warned);
}
