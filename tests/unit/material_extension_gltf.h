// Small glTF files for the material extensions, written at test time (test_material_extensions.cpp and
// tests/gpu/test_material_extensions.cpp): UV spheres in a row, each with one material, the textures PNGs written
// with OpenImageIO (no committed binaries; REQUIRE_OIIO skips the tests in a build without it).
//   extensions.gltf   KHR_materials_unlit (textured), KHR_materials_clearcoat with factors only, clearcoat with its
//                     three textures (weight R, roughness G, a bumpy coat normal), KHR_materials_emissive_strength
//                     (emissive x 3: radiance above 1), and a clearcoat over a double-sided normal-mapped base.
//   metal_rough.gltf  a textured metal-rough sphere (base colour and metallic-roughness gradients) and a
//                     factors-only one.
//   spec_gloss.gltf   their KHR_materials_pbrSpecularGlossiness twins: the same surfaces (c_diff and f0 per texel
//                     computed from the metal-rough texels), for the conversion's render comparison.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "test_assets.h"  // (test::base64)
#include "visbuf/asset/texture_bake.h"  // (srgbToLinear, encodeSrgb8)

namespace visbuf::test {

// Writes width x height RGBA8 to dir/name as a PNG (TextureTest::writePng).
using PngWriter = std::function<void(const std::string& name, uint32_t width, uint32_t height,
                                     const std::vector<uint8_t>& rgba)>;

inline constexpr uint32_t kExtTextureSize = 32;
inline constexpr size_t kExtSpheres = 5;  // spheres of extensions.gltf, left to right

// A metal-rough texel of the twins' textures at (x, y): base colour (sRGB codes), roughness and metallic codes.
inline glm::u8vec4 twinBaseTexel(uint32_t x, uint32_t y) {
  return {uint8_t(60 + 6 * x), uint8_t(200 - 5 * y), uint8_t(40 + 3 * (x + y)), 255};
}
inline glm::u8vec4 twinMetalRoughTexel(uint32_t x, uint32_t y) {
  return {255, uint8_t(40 + 6 * y), uint8_t(std::min(255u, 8 * x + 4)), 255};  // G roughness, B metallic
}

// The spec-gloss surface equal to metal-rough (base, metallic, roughness): f0 = 0.04 (1 - m) + base m, c_diff =
// base (1 - m) = diffuse (1 - max(f0)), glossiness = 1 - roughness. Linear values; diffuse clamped to 1 (above
// only where max(f0) > 0.04 + 0.96 m, which metal-rough's own f0 never is by more than rounding).
struct SpecGlossTwin {
  glm::dvec3 diffuse, specular;
  double glossiness;
};
inline SpecGlossTwin specGlossTwin(const glm::dvec3& base, double metallic, double roughness) {
  SpecGlossTwin t;
  t.specular = glm::dvec3(0.04) * (1.0 - metallic) + base * metallic;
  const double maxF0 = std::max({t.specular.r, t.specular.g, t.specular.b});
  t.diffuse = glm::clamp(base * (1.0 - metallic) / std::max(1.0 - maxF0, 1e-9), 0.0, 1.0);
  t.glossiness = 1.0 - roughness;
  return t;
}

// A UV sphere of radius 1: POSITION, NORMAL, TEXCOORD_0 (u around, v from the north pole), 16-bit indices;
// returns the glTF buffers / bufferViews / accessors (accessors 0..3) of one embedded buffer.
inline nlohmann::json sphereBuffers(int rings = 24, int segments = 48) {
  std::vector<float> pos, nrm, uv;
  std::vector<uint16_t> idx;
  for (int r = 0; r <= rings; ++r) {
    const double theta = M_PI * r / rings;
    for (int s = 0; s <= segments; ++s) {
      const double phi = 2.0 * M_PI * s / segments;
      const glm::dvec3 n(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi));
      for (int k = 0; k < 3; ++k) {
        pos.push_back(float(n[k]));
        nrm.push_back(float(n[k]));
      }
      uv.push_back(float(double(s) / segments));
      uv.push_back(float(double(r) / rings));
    }
  }
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const auto a = uint16_t(r * (segments + 1) + s), b = uint16_t(a + segments + 1);
      idx.insert(idx.end(), {a, b, uint16_t(a + 1), uint16_t(a + 1), b, uint16_t(b + 1)});
    }
  std::vector<uint8_t> bytes;
  auto append = [&](const void* p, size_t n) {
    const size_t at = bytes.size();
    bytes.resize(at + n);
    std::memcpy(bytes.data() + at, p, n);
    return at;
  };
  const size_t pOff = append(pos.data(), pos.size() * 4), nOff = append(nrm.data(), nrm.size() * 4);
  const size_t uOff = append(uv.data(), uv.size() * 4), iOff = append(idx.data(), idx.size() * 2);
  const size_t vertices = pos.size() / 3;
  auto view = [](size_t offset, size_t length) {
    return nlohmann::json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}};
  };
  return {{"buffers", {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + base64(bytes)}}}},
          {"bufferViews", {view(pOff, pos.size() * 4), view(nOff, nrm.size() * 4), view(uOff, uv.size() * 4),
                           view(iOff, idx.size() * 2)}},
          {"accessors",
           {{{"bufferView", 0}, {"componentType", 5126}, {"count", vertices}, {"type", "VEC3"},
             {"min", {-1, -1, -1}}, {"max", {1, 1, 1}}},
            {{"bufferView", 1}, {"componentType", 5126}, {"count", vertices}, {"type", "VEC3"}},
            {{"bufferView", 2}, {"componentType", 5126}, {"count", vertices}, {"type", "VEC2"}},
            {{"bufferView", 3}, {"componentType", 5123}, {"count", idx.size()}, {"type", "SCALAR"}}}}};
}

// A document of one sphere per material, in a row along x (2.5 apart), with `images` (URIs) as textures
// 0.. in order.
inline nlohmann::json sphereRowDoc(const nlohmann::json& materials, const std::vector<std::string>& images,
                                   const std::vector<std::string>& extensionsUsed) {
  nlohmann::json doc = sphereBuffers();
  doc["asset"] = {{"version", "2.0"}};
  if (!extensionsUsed.empty()) doc["extensionsUsed"] = extensionsUsed;
  doc["images"] = nlohmann::json::array();
  doc["textures"] = nlohmann::json::array();
  for (size_t i = 0; i < images.size(); ++i) {
    doc["images"].push_back({{"uri", images[i]}});
    doc["textures"].push_back({{"source", i}});
  }
  if (images.empty()) {
    doc.erase("images");
    doc.erase("textures");
  }
  doc["materials"] = materials;
  doc["meshes"] = nlohmann::json::array();
  doc["nodes"] = nlohmann::json::array();
  nlohmann::json roots = nlohmann::json::array();
  for (size_t i = 0; i < materials.size(); ++i) {
    const nlohmann::json primitive = {{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}}},
                                      {"indices", 3},
                                      {"material", i}};
    doc["meshes"].push_back({{"primitives", nlohmann::json::array({primitive})}});
    doc["nodes"].push_back({{"mesh", i}, {"translation", {2.5 * double(i), 0.0, 0.0}}});
    roots.push_back(i);
  }
  doc["scenes"] = {{{"nodes", roots}}};
  doc["scene"] = 0;
  return doc;
}

struct MaterialExtensionFiles {
  std::filesystem::path extensions, metalRough, specGloss;
};

// Writes the three files (and their PNGs) into `dir`.
inline MaterialExtensionFiles writeMaterialExtensionFiles(const std::filesystem::path& dir, const PngWriter& png) {
  using nlohmann::json;
  const uint32_t n = kExtTextureSize;
  std::vector<uint8_t> colour(n * n * 4), coat(n * n * 4), coatNormal(n * n * 4), base(n * n * 4), mr(n * n * 4),
      diffuse(n * n * 4), specGloss(n * n * 4);
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      const size_t i = (size_t(y) * n + x) * 4;
      const uint8_t c[4] = {uint8_t(255 - 6 * x), uint8_t(120 + 4 * y), uint8_t(30 + 7 * ((x + y) % 16)), 255};
      std::copy(c, c + 4, &colour[i]);
      // Coat weight along x (R), coat roughness along y (G).
      const uint8_t w[4] = {uint8_t(40 + 6 * x), uint8_t(8 * y), 0, 255};
      std::copy(w, w + 4, &coat[i]);
      // Coat normal: bumps of tangent-space slope up to ~0.35.
      const double sx = 0.35 * std::sin(2.0 * M_PI * x / 8.0), sy = 0.35 * std::cos(2.0 * M_PI * y / 8.0);
      const glm::dvec3 tn = glm::normalize(glm::dvec3(sx, sy, 1.0));
      for (int k = 0; k < 3; ++k) coatNormal[i + size_t(k)] = uint8_t(std::lround((tn[k] * 0.5 + 0.5) * 255.0));
      coatNormal[i + 3] = 255;
      const glm::u8vec4 b = twinBaseTexel(x, y), t = twinMetalRoughTexel(x, y);
      for (int k = 0; k < 4; ++k) {
        base[i + size_t(k)] = b[k];
        mr[i + size_t(k)] = t[k];
      }
      const glm::dvec3 linear(srgbToLinear(b.r / 255.0f), srgbToLinear(b.g / 255.0f), srgbToLinear(b.b / 255.0f));
      const SpecGlossTwin sg = specGlossTwin(linear, t.b / 255.0, t.g / 255.0);
      for (int k = 0; k < 3; ++k) {
        diffuse[i + size_t(k)] = encodeSrgb8(float(sg.diffuse[k]));
        specGloss[i + size_t(k)] = encodeSrgb8(float(sg.specular[k]));
      }
      diffuse[i + 3] = 255;
      specGloss[i + 3] = uint8_t(std::lround(sg.glossiness * 255.0));
    }
  png("colour.png", n, n, colour);
  png("coat.png", n, n, coat);
  png("coat_normal.png", n, n, coatNormal);
  png("base.png", n, n, base);
  png("mr.png", n, n, mr);
  png("diffuse.png", n, n, diffuse);
  png("specgloss.png", n, n, specGloss);

  MaterialExtensionFiles files{dir / "extensions.gltf", dir / "metal_rough.gltf", dir / "spec_gloss.gltf"};
  const json unlit = {{"name", "unlit"},
                      {"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 0.8, 0.7, 1.0}}, {"baseColorTexture", {{"index", 0}}}}},
                      {"extensions", {{"KHR_materials_unlit", json::object()}}}};
  const json coatFactors = {
      {"name", "clearcoat"},
      {"pbrMetallicRoughness", {{"baseColorFactor", {0.7, 0.05, 0.03, 1.0}}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.8}}},
      {"extensions", {{"KHR_materials_clearcoat", {{"clearcoatFactor", 1.0}, {"clearcoatRoughnessFactor", 0.1}}}}}};
  const json coatTextured = {
      {"name", "clearcoat textured"},
      {"pbrMetallicRoughness", {{"baseColorFactor", {0.1, 0.2, 0.6, 1.0}}, {"metallicFactor", 0.3}, {"roughnessFactor", 0.6}}},
      {"extensions",
       {{"KHR_materials_clearcoat",
         {{"clearcoatFactor", 0.9},
          {"clearcoatTexture", {{"index", 1}}},
          {"clearcoatRoughnessFactor", 0.6},
          {"clearcoatRoughnessTexture", {{"index", 1}}},
          {"clearcoatNormalTexture", {{"index", 2}, {"scale", 0.7}}}}}}}};
  const json emissive = {{"name", "emissive x3"},
                         {"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.2, 0.2, 1.0}}, {"metallicFactor", 0.0}}},
                         {"emissiveFactor", {1.0, 0.5, 0.25}},
                         {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 3.0}}}}}};
  const json coatOverNormalMap = {
      {"name", "clearcoat over normal map"},
      {"doubleSided", true},
      {"normalTexture", {{"index", 2}, {"scale", 1.0}}},
      {"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 0.7, 0.2, 1.0}}, {"metallicFactor", 1.0}, {"roughnessFactor", 0.5}}},
      {"extensions", {{"KHR_materials_clearcoat", {{"clearcoatFactor", 0.5}, {"clearcoatRoughnessFactor", 0.3}}}}}};
  std::ofstream(files.extensions) << sphereRowDoc({unlit, coatFactors, coatTextured, emissive, coatOverNormalMap},
                                                  {"colour.png", "coat.png", "coat_normal.png"},
                                                  {"KHR_materials_unlit", "KHR_materials_clearcoat",
                                                   "KHR_materials_emissive_strength"})
                                         .dump(1);

  // The twins: a textured sphere and a factors-only one (a half-metallic coloured surface, which the conversion
  // cannot match exactly).
  const glm::dvec3 factorBase(0.8, 0.5, 0.2);
  const double factorMetallic = 0.5, factorRoughness = 0.35;
  const json mrTextured = {{"name", "metal-rough textured"},
                           {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicRoughnessTexture", {{"index", 1}}}}}};
  const json mrFactors = {{"name", "metal-rough factors"},
                          {"pbrMetallicRoughness",
                           {{"baseColorFactor", {factorBase.r, factorBase.g, factorBase.b, 1.0}},
                            {"metallicFactor", factorMetallic},
                            {"roughnessFactor", factorRoughness}}}};
  std::ofstream(files.metalRough) << sphereRowDoc({mrTextured, mrFactors}, {"base.png", "mr.png"}, {}).dump(1);
  const SpecGlossTwin t = specGlossTwin(factorBase, factorMetallic, factorRoughness);
  const json sgTextured = {
      {"name", "spec-gloss textured"},
      {"extensions",
       {{"KHR_materials_pbrSpecularGlossiness", {{"diffuseTexture", {{"index", 0}}}, {"specularGlossinessTexture", {{"index", 1}}}}}}}};
  const json sgFactors = {
      {"name", "spec-gloss factors"},
      {"extensions",
       {{"KHR_materials_pbrSpecularGlossiness",
         {{"diffuseFactor", {t.diffuse.r, t.diffuse.g, t.diffuse.b, 1.0}},
          {"specularFactor", {t.specular.r, t.specular.g, t.specular.b}},
          {"glossinessFactor", t.glossiness}}}}}};
  std::ofstream(files.specGloss) << sphereRowDoc({sgTextured, sgFactors}, {"diffuse.png", "specgloss.png"},
                                                 {"KHR_materials_pbrSpecularGlossiness"})
                                        .dump(1);
  return files;
}

}  // namespace visbuf::test
