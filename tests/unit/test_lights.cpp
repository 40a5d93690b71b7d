// Lights on the CPU: the BRDF reference against closed-form values of the glTF 2.0 appendix B formulas,
// point, spot and directional light validation, point light scattering, KHR_lights_punctual import.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>
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
  }
  EXPECT_TRUE(validateScene(scene).ok());
}

// Range and intensity on a scene whose bounds are known by hand: two objects of one mesh with a bounding sphere of
// radius 5 at its origin, placed at (0, 0, 0) and (10, 10, 10). The box of their bounds is [-5, 15]^3: 20 units a
// side, 8000 cubic units.
//   1000 lights: mean spacing cbrt(8000 / 1000) = 2, range 1.5 x 2 = 3, intensity 0.5 x 3^2 = 4.5.
//   8 lights: spacing cbrt(8000 / 8) = 10, range 15, intensity 0.5 x 225 = 112.5.
// Up to the bounds' padding: objectBoundsWorld scales a radius by an upper bound of the transform's scale, 1 + 1e-6
// for these, so the box's side is 20 + 1e-5 and the spacing, the range and the square root of the intensity grow by
// 5e-7 relative (bounds below: 1e-6 relative). The header's consequences, by brute force over the 1000 lights: a point at least one range
// inside the box sees on average (4/3) pi 1.5^3 = 14.14 lights within their range (bound +-3: the lights near the
// ~2700 sampled cubic units number ~340, whose binomial spread moves the mean by ~5 %); and a light at half its range
// gives irradiance 4.5 / 1.5^2 x (1 - 0.5^4)^2 = 2 x 0.87890625 = 1.7578125 (the 1/d^2 falloff and its window of
// light.h).
TEST(LightsCpu, ScatterRangeAndIntensityFollowTheSpacing) {
  Scene scene;
  Mesh mesh;
  mesh.boundsSphere = {0.0f, 0.0f, 0.0f, 5.0f};
  scene.meshes.push_back(mesh);
  scene.objects.push_back({glm::dmat4(1.0), 0, 0});
  scene.objects.push_back({glm::translate(glm::dmat4(1.0), glm::dvec3(10.0)), 0, 0});
  Scene few = scene;
  scatterPointLights(few, 8, 5);
  ASSERT_EQ(few.pointLights.size(), 8u);
  for (const PointLight& l : few.pointLights) {
    EXPECT_NEAR(l.range, 15.0f, 15.0f * 1e-6f);
    EXPECT_NEAR(l.intensity, 112.5f, 112.5f * 2e-6f);
  }
  scatterPointLights(scene, 1000, 3);
  ASSERT_EQ(scene.pointLights.size(), 1000u);
  glm::dvec3 mean(0.0);
  for (const PointLight& l : scene.pointLights) {
    EXPECT_NEAR(l.range, 3.0f, 3.0f * 1e-6f);
    EXPECT_NEAR(l.intensity, 4.5f, 4.5f * 2e-6f);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(l.position[a], -5.0 - 1e-5);
      EXPECT_LE(l.position[a], 15.0 + 1e-5);
    }
    // A saturated hue: one channel full, one off.
    EXPECT_EQ(std::max({l.color.r, l.color.g, l.color.b}), 1.0f);
    EXPECT_EQ(std::min({l.color.r, l.color.g, l.color.b}), 0.0f);
    mean += l.position / 1000.0;
  }
  // Uniform over the box: the mean position within 0.6 per axis (about 3 standard deviations, 20 / sqrt(12 x 1000))
  // of (5, 5, 5).
  EXPECT_LT(glm::length(mean - glm::dvec3(5.0)), 0.6 * std::sqrt(3.0)) << mean.x << " " << mean.y << " " << mean.z;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> inside(-2.0, 12.0);  // 3 (one range) from every face of the box
  size_t seen = 0;
  const int points = 2000;
  for (int i = 0; i < points; ++i) {
    const glm::dvec3 p(inside(rng), inside(rng), inside(rng));
    for (const PointLight& l : scene.pointLights) seen += glm::length(l.position - p) < double(l.range);
  }
  EXPECT_NEAR(double(seen) / points, 4.0 / 3.0 * std::numbers::pi * 1.5 * 1.5 * 1.5, 3.0);
  const double d = 0.5 * double(scene.pointLights[0].range);
  const double window = std::pow(1.0 - std::pow(0.5, 4.0), 2.0);
  EXPECT_NEAR(double(scene.pointLights[0].intensity) * window / (d * d), 1.7578125, 1e-5);
}

class LightImportTest : public test::TempDirTest {};

// A triangle at the origin and three KHR_lights_punctual lights: a point light on a translated, scaled node
// (position from the node's world transform, range and intensity as written, not scaled by the node); a spot
// light on a node rotated -90 degrees about +X and scaled by 3 (its -Z becomes -Y: the direction is the node's
// -Z, renormalised), with its cone angles; a directional light on a node rotated 90 degrees about +Y (-Z becomes
// -X), whose range is ignored.
TEST_F(LightImportTest, KhrLightsPunctualPointSpotDirectional) {
  std::vector<uint8_t> bytes(36);
  const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(bytes.data(), tri, sizeof(tri));
  const double h = std::sqrt(0.5);  // quaternion (x, y, z, w) of a 90-degree turn: sin 45, cos 45
  nlohmann::json doc = {
      {"asset", {{"version", "2.0"}}},
      {"extensionsUsed", {"KHR_lights_punctual"}},
      {"extensions",
       {{"KHR_lights_punctual",
         {{"lights",
           {{{"type", "point"}, {"color", {1.0, 0.5, 0.25}}, {"intensity", 7.0}, {"range", 12.0}},
            {{"type", "spot"}, {"name", "cone"}, {"intensity", 40.0}, {"range", 30.0},
             {"spot", {{"innerConeAngle", 0.25}, {"outerConeAngle", 0.5}}}},
            {{"type", "directional"}, {"color", {0.5, 0.5, 1.0}}, {"intensity", 3.0}}}}}}}},
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
        {{"rotation", {-h, 0.0, 0.0, h}}, {"scale", {3.0, 3.0, 3.0}},
         {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}},
        {{"rotation", {0.0, h, 0.0, h}}, {"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}}}},
      {"scenes", {{{"nodes", {0, 1, 4}}}}},
      {"scene", 0}};
  const std::string path = (dir_ / "light.gltf").string();
  std::ofstream(path) << doc.dump();
  GltfImportReport report;
  Result<ImportedScene> s = importGltfScene(path, {}, &report);
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_TRUE(report.warnings.empty()) << report.warnings.front();
  ASSERT_EQ(s->pointLights.size(), 3u);
  const PointLight& l = s->pointLights[0];
  EXPECT_EQ(l.type, LightType::Point);
  EXPECT_EQ(l.position, glm::dvec3(1.0, 2.0, 8.0));
  EXPECT_EQ(l.color, glm::vec3(1.0f, 0.5f, 0.25f));
  EXPECT_EQ(l.intensity, 7.0f);
  EXPECT_EQ(l.range, 12.0f);
  const PointLight& spot = s->pointLights[1];
  EXPECT_EQ(spot.type, LightType::Spot);
  EXPECT_EQ(spot.position, glm::dvec3(1.0, 2.0, 3.0));
  EXPECT_EQ(spot.intensity, 40.0f);
  EXPECT_EQ(spot.range, 30.0f);
  EXPECT_EQ(spot.color, glm::vec3(1.0f));  // the extension's default colour
  EXPECT_LT(glm::length(glm::dvec3(spot.direction) - glm::dvec3(0.0, -1.0, 0.0)), 1e-6);
  EXPECT_EQ(spot.innerConeAngle, 0.25f);
  EXPECT_EQ(spot.outerConeAngle, 0.5f);
  const PointLight& sun = s->pointLights[2];
  EXPECT_EQ(sun.type, LightType::Directional);
  EXPECT_LT(glm::length(glm::dvec3(sun.direction) - glm::dvec3(-1.0, 0.0, 0.0)), 1e-6);
  EXPECT_EQ(sun.color, glm::vec3(0.5f, 0.5f, 1.0f));
  EXPECT_EQ(sun.intensity, 3.0f);
  EXPECT_EQ(sun.range, 0.0f);
  // The cone as the GPU gets it: KHR_lights_punctual's scale / offset, checked at the two edges (attenuation
  // 1 at the inner angle, 0 at the outer one).
  const glm::dvec2 so = spotAngleScaleOffset(spot);
  EXPECT_NEAR(std::cos(0.25) * so.x + so.y, 1.0, 1e-6);
  EXPECT_NEAR(std::cos(0.5) * so.x + so.y, 0.0, 1e-6);
  EXPECT_EQ(spotAngleScaleOffset(l), glm::dvec2(0.0, 1.0));
}

// Spot cone angles outside 0 <= inner < outer <= pi/2 and unusable parameters are refused with a message that
// names the node and the light; an unknown light type is skipped with a warning.
TEST_F(LightImportTest, KhrLightsPunctualBadParametersAreRefused) {
  std::vector<uint8_t> bytes(36);
  const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(bytes.data(), tri, sizeof(tri));
  auto importLight = [&](const nlohmann::json& light, const nlohmann::json& lightNode, GltfImportReport* report) {
    nlohmann::json node = lightNode;
    node["name"] = "lamp";
    node["extensions"] = {{"KHR_lights_punctual", {{"light", 0}}}};
    nlohmann::json doc = {
        {"asset", {{"version", "2.0"}}},
        {"extensionsUsed", {"KHR_lights_punctual"}},
        {"extensions", {{"KHR_lights_punctual", {{"lights", {light}}}}}},
        {"buffers", {{{"byteLength", 36}, {"uri", "data:application/octet-stream;base64," + test::base64(bytes)}}}},
        {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}}},
        {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
        {"nodes", {{{"mesh", 0}}, node}},
        {"scenes", {{{"nodes", {0, 1}}}}}};
    const std::string path = (dir_ / "bad_light.gltf").string();
    std::ofstream(path) << doc.dump();
    return importGltfScene(path, {}, report);
  };
  const nlohmann::json plainNode = nlohmann::json::object();
  struct Case {
    nlohmann::json light;
    nlohmann::json node;
    const char* message;
  };
  const double pi = std::numbers::pi;
  const Case cases[] = {
      {{{"type", "spot"}, {"spot", {{"innerConeAngle", 0.5}, {"outerConeAngle", 0.5}}}}, plainNode,
       "need 0 <= inner < outer <= pi/2"},
      {{{"type", "spot"}, {"spot", {{"innerConeAngle", 0.6}, {"outerConeAngle", 0.5}}}}, plainNode,
       "need 0 <= inner < outer <= pi/2"},
      {{{"type", "spot"}, {"spot", {{"innerConeAngle", -0.1}, {"outerConeAngle", 0.5}}}}, plainNode,
       "need 0 <= inner < outer <= pi/2"},
      {{{"type", "spot"}, {"spot", {{"outerConeAngle", pi / 2 + 0.01}}}}, plainNode, "need 0 <= inner < outer <= pi/2"},
      {{{"type", "spot"}, {"range", -1.0}, {"spot", {{"outerConeAngle", 0.5}}}}, plainNode,
       "negative or non-finite range"},
      {{{"type", "point"}, {"intensity", -2.0}}, plainNode, "negative intensity or colour"},
      {{{"type", "directional"}}, {{"scale", {1.0, 1.0, 0.0}}}, "maps -Z to a zero or non-finite direction"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.light.dump());
    Result<ImportedScene> s = importLight(c.light, c.node, nullptr);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.error().code, ErrorCode::MalformedInput);
    EXPECT_NE(s.error().message.find(c.message), std::string::npos) << s.error().message;
    EXPECT_NE(s.error().message.find("node 1 'lamp': KHR_lights_punctual light 0"), std::string::npos)
        << s.error().message;
  }
  // A colour of 2 numbers: refused before parsing, naming the JSON path (gltf_validate.h).
  Result<ImportedScene> shortColor = importLight({{"type", "directional"}, {"color", {1.0, 1.0}}}, plainNode, nullptr);
  ASSERT_FALSE(shortColor.ok());
  EXPECT_NE(shortColor.error().message.find("extensions.KHR_lights_punctual.lights[0].color: has 2 elements, expected 3"),
            std::string::npos)
      << shortColor.error().message;
  // The bounds themselves are valid: inner 0, outer pi/2.
  Result<ImportedScene> wide =
      importLight({{"type", "spot"}, {"spot", {{"outerConeAngle", pi / 2}}}}, plainNode, nullptr);
  ASSERT_TRUE(wide.ok()) << wide.error().message;
  EXPECT_EQ(wide->pointLights.size(), 1u);
  GltfImportReport report;
  Result<ImportedScene> unknown = importLight({{"type", "area"}}, plainNode, &report);
  ASSERT_TRUE(unknown.ok()) << unknown.error().message;
  EXPECT_TRUE(unknown->pointLights.empty());
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("unknown type 'area'"), std::string::npos) << report.warnings[0];
}

// The CPU reference's spot and directional terms against closed forms: a surface facing a spot light along its
// axis gets the point light's value inside the inner cone, exactly the quadratic cone factor between the angles
// and nothing beyond the outer one; a directional light equals the scene's own sun of the same direction.
TEST(LightsCpu, SpotAndDirectionalReference) {
  Scene scene;
  scene.lightIntensity = 0.0f;
  SurfaceReference s;
  s.position = {0.0, 0.0, -10.0};
  s.normal = {0.0, 0.0, 1.0};
  PointLight point;
  point.position = {0.0, 0.0, -6.0};  // 4 in front of the surface
  point.intensity = 50.0f;
  point.range = 0.0f;
  scene.pointLights = {point};
  const glm::dvec3 pointOnly = shadeReference(s, scene, glm::dvec3(0.0));
  scene.pointLights.clear();
  const glm::dvec3 ambient = shadeReference(s, scene, glm::dvec3(0.0));
  PointLight spot = point;
  spot.type = LightType::Spot;
  spot.innerConeAngle = 0.2f;
  spot.outerConeAngle = 0.4f;
  for (double angle : {0.0, 0.1, 0.25, 0.3, 0.35, 0.45}) {
    SCOPED_TRACE(angle);
    // Tilt the spot's axis away from the surface point by `angle` (about +Y).
    spot.direction = glm::vec3(float(std::sin(angle)), 0.0f, float(-std::cos(angle)));
    scene.pointLights = {spot};
    const glm::dvec3 lit = shadeReference(s, scene, glm::dvec3(0.0));
    const double cd = std::cos(double(float(angle)));
    const double t = std::clamp((cd - std::cos(0.4)) / (std::cos(0.2) - std::cos(0.4)), 0.0, 1.0);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(lit[c] - ambient[c], (pointOnly[c] - ambient[c]) * t * t, 1e-5);
  }
  PointLight sun;
  sun.type = LightType::Directional;
  sun.direction = glm::normalize(glm::vec3(0.3f, -0.2f, -1.0f));
  sun.intensity = 2.5f;
  sun.color = glm::vec3(1.0f, 0.5f, 0.25f);
  scene.pointLights = {sun};
  const glm::dvec3 viaLight = shadeReference(s, scene, glm::dvec3(0.0));
  Scene sunScene;
  sunScene.lightDirection = -sun.direction;
  sunScene.lightIntensity = 2.5f;
  const glm::dvec3 viaSun = shadeReference(s, sunScene, glm::dvec3(0.0));
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(viaLight[c] - ambient[c], (viaSun[c] - ambient[c]) * double(sun.color[c]), 1e-9);
  EXPECT_GT(viaLight.x - ambient.x, 0.1);
}

// validatePointLights: spot angles and directions.
TEST(LightsCpu, SpotAndDirectionalValidation) {
  PointLight spot;
  spot.type = LightType::Spot;
  spot.innerConeAngle = 0.3f;
  spot.outerConeAngle = 0.3f;
  EXPECT_FALSE(validatePointLights({spot}).ok());
  spot.innerConeAngle = 0.1f;
  EXPECT_TRUE(validatePointLights({spot}).ok());
  spot.outerConeAngle = 1.6f;
  EXPECT_FALSE(validatePointLights({spot}).ok());
  spot.outerConeAngle = 0.5f;
  spot.direction = glm::vec3(0.0f, 0.0f, -2.0f);
  EXPECT_FALSE(validatePointLights({spot}).ok());
  PointLight sun;
  sun.type = LightType::Directional;
  sun.direction = glm::vec3(0.0f);
  EXPECT_FALSE(validatePointLights({sun}).ok());
  sun.direction = glm::vec3(0.0f, -1.0f, 0.0f);
  EXPECT_TRUE(validatePointLights({sun}).ok());
}
