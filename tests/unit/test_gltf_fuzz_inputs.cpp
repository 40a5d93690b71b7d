// Hand-built glTF inputs of the GltfFuzz suite: the two seed files that the fuzzer of test_gltf_fuzz.cpp mutates
// (makeSkinnedGlb, makeDataUriGltf) and the inputs the fuzzer found, minimized, as regression tests.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gltf_fuzz_helpers.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/scene.h"

namespace visbuf {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr int kUByte = 5121;
constexpr int kUShort = 5123;
constexpr int kFloat = 5126;

// --- seed files
// ---------------------------------------------------------------------------------------------

// One binary buffer with bufferViews and accessors appended to a JSON document.
class BinBuilder {
 public:
  explicit BinBuilder(json& doc) : doc_(doc) {}

  template <typename T>
  int view(const std::vector<T>& values, std::optional<int> byteStride = std::nullopt) {
    while (bytes_.size() % 4 != 0) bytes_.push_back(0);
    const size_t offset = bytes_.size();
    bytes_.resize(offset + values.size() * sizeof(T));
    std::memcpy(bytes_.data() + offset, values.data(), values.size() * sizeof(T));
    json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * sizeof(T)}};
    if (byteStride) v["byteStride"] = *byteStride;
    doc_["bufferViews"].push_back(v);
    return static_cast<int>(doc_["bufferViews"].size()) - 1;
  }
  int accessor(json a) {
    doc_["accessors"].push_back(std::move(a));
    return static_cast<int>(doc_["accessors"].size()) - 1;
  }
  template <typename T>
  int add(const std::vector<T>& values, int componentType, const char* type, size_t count, bool normalized = false) {
    json a = {{"bufferView", view(values)}, {"componentType", componentType}, {"count", count}, {"type", type}};
    if (normalized) a["normalized"] = true;
    return accessor(std::move(a));
  }
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  json& doc_;
  std::vector<uint8_t> bytes_;
};

using test::makeGlb;
using test::base64;
using test::gltf_fuzz::GltfFuzz;
using test::gltf_fuzz::writeFile;

}  // namespace

namespace test::gltf_fuzz {

// A .glb: an indexed quad skinned to a 2-joint chain (node 0), the same quad with a sparse morph target under
// a mirroring node (node 3), a material with an embedded texture, and an animation with LINEAR rotation, STEP
// translation and weights channels.
std::vector<uint8_t> makeSkinnedGlb() {
  json doc = {{"asset", {{"version", "2.0"}}}, {"scene", 0}};
  BinBuilder b(doc);
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const int pos = b.accessor({{"bufferView", b.view(positions)},
                              {"componentType", kFloat},
                              {"count", 4},
                              {"type", "VEC3"},
                              {"min", {0, 0, 0}},
                              {"max", {1, 1, 0}}});
  const int nrm = b.add(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, kFloat, "VEC3", 4);
  const int uv = b.add(std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}, kFloat, "VEC2", 4);
  const int joints = b.add(std::vector<uint8_t>{0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0}, kUByte, "VEC4", 4);
  const int weights =
      b.add(std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, 0.5f, 0.5f, 0, 0, 0.25f, 0.75f, 0, 0}, kFloat, "VEC4", 4);
  const int idx = b.add(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}, kUShort, "SCALAR", 6);
  std::vector<float> ibm(32, 0.0f);
  for (int m = 0; m < 2; ++m)
    for (int d = 0; d < 4; ++d) ibm[size_t(16 * m + 5 * d)] = 1.0f;
  ibm[16 + 13] = -1.0f;  // joint 1 sits at y = 1
  const int ibmAcc = b.add(ibm, kFloat, "MAT4", 2);
  // Sparse morph target: no bufferView, vertex 2 moves by +z.
  const int sparseIdx = b.view(std::vector<uint8_t>{2});
  const int sparseVal = b.view(std::vector<float>{0, 0, 0.5f});
  const int morph = b.accessor({{"componentType", kFloat},
                                {"count", 4},
                                {"type", "VEC3"},
                                {"sparse",
                                 {{"count", 1},
                                  {"indices", {{"bufferView", sparseIdx}, {"componentType", kUByte}}},
                                  {"values", {{"bufferView", sparseVal}}}}}});
  const int times = b.add(std::vector<float>{0, 1}, kFloat, "SCALAR", 2);
  const int rot = b.add(std::vector<float>{0, 0, 0, 1, 0, 0, 0.38268343f, 0.92387953f}, kFloat, "VEC4", 2);
  const int trans = b.add(std::vector<float>{0, 0, 0, 0.5f, 0, 0}, kFloat, "VEC3", 2);
  const int wts = b.add(std::vector<float>{0, 1}, kFloat, "SCALAR", 2);
  const int image = b.view(std::vector<uint8_t>{0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A});

  doc["meshes"] = json::array(
      {{{"name", "skinned"},
        {"primitives",
         {{{"attributes",
            {{"POSITION", pos}, {"NORMAL", nrm}, {"TEXCOORD_0", uv}, {"JOINTS_0", joints}, {"WEIGHTS_0", weights}}},
           {"indices", idx},
           {"material", 0}}}}},
       {{"name", "morphed"},
        {"weights", {0.5}},
        {"primitives",
         {{{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}},
           {"indices", idx},
           {"material", 0},
           {"targets", {{{"POSITION", morph}}}}}}}}});
  doc["nodes"] = json::array({{{"name", "skinned"}, {"mesh", 0}, {"skin", 0}},
                              {{"name", "root"}, {"translation", {0, 0, 0}}, {"children", {2}}},
                              {{"name", "tip"}, {"translation", {0, 1, 0}}},
                              {{"name", "mirror"}, {"mesh", 1}, {"scale", {-1, 1, 1}}, {"translation", {3, 0, 0}}}});
  doc["scenes"] = json::array({{{"nodes", {0, 1, 3}}}});
  doc["skins"] = json::array({{{"joints", {1, 2}}, {"inverseBindMatrices", ibmAcc}, {"skeleton", 1}}});
  doc["animations"] = json::array(
      {{{"name", "wave"},
        {"samplers",
         {{{"input", times}, {"output", rot}},
          {{"input", times}, {"output", trans}, {"interpolation", "STEP"}},
          {{"input", times}, {"output", wts}}}},
        {"channels",
         {{{"sampler", 0}, {"target", {{"node", 2}, {"path", "rotation"}}}},
          {{"sampler", 1}, {"target", {{"node", 1}, {"path", "translation"}}}},
          {{"sampler", 2}, {"target", {{"node", 3}, {"path", "weights"}}}}}}}});
  doc["materials"] = json::array({{{"name", "mat"},
                                   {"pbrMetallicRoughness",
                                    {{"baseColorFactor", {1, 0.5, 0.25, 1}},
                                     {"metallicFactor", 0.5},
                                     {"roughnessFactor", 0.5},
                                     {"baseColorTexture", {{"index", 0}}}}},
                                   {"normalTexture", {{"index", 0}, {"scale", 1}}},
                                   {"alphaMode", "MASK"},
                                   {"alphaCutoff", 0.3},
                                   {"doubleSided", true}}});
  doc["images"] = json::array({{{"bufferView", image}, {"mimeType", "image/png"}}});
  doc["samplers"] = json::array({{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 33648}}});
  doc["textures"] = json::array({{{"source", 0}, {"sampler", 0}}});
  doc["buffers"] = json::array({{{"byteLength", b.bytes().size()}}});
  return makeGlb(doc.dump(), b.bytes());
}

// A .gltf with its buffer as a data: URI: interleaved position+normal (byteStride 24), quantized uvs and
// colours, tangents, u8 indices, a TRIANGLES and a TRIANGLE_STRIP primitive, a matrix parent and a TRS child.
std::string makeDataUriGltf() {
  json doc = {{"asset", {{"version", "2.0"}}}};
  BinBuilder b(doc);
  const std::vector<float> interleaved = {0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 1, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1};
  const int view = b.view(interleaved, 24);
  const int pos = b.accessor({{"bufferView", view},
                              {"componentType", kFloat},
                              {"count", 4},
                              {"type", "VEC3"},
                              {"min", {0, 0, 0}},
                              {"max", {1, 1, 0}}});
  const int nrm = b.accessor({{"bufferView", view}, {"byteOffset", 12}, {"componentType", kFloat}, {"count", 4},
                              {"type", "VEC3"}});
  const int uv = b.add(std::vector<uint16_t>{0, 0, 65535, 0, 65535, 65535, 0, 65535}, kUShort, "VEC2", 4, true);
  const int color = b.add(std::vector<uint8_t>{255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128},
                          kUByte, "VEC4", 4, true);
  const int tangent = b.add(std::vector<float>{1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1}, kFloat, "VEC4", 4);
  const int idx = b.add(std::vector<uint8_t>{0, 1, 2, 0, 2, 3}, kUByte, "SCALAR", 6);
  const int strip = b.add(std::vector<uint8_t>{0, 1, 3, 2}, kUByte, "SCALAR", 4);
  const json attributes = {
      {"POSITION", pos}, {"NORMAL", nrm}, {"TEXCOORD_0", uv}, {"COLOR_0", color}, {"TANGENT", tangent}};
  doc["meshes"] = json::array({{{"name", "quad"},
                                {"primitives",
                                 {{{"attributes", attributes}, {"indices", idx}, {"material", 0}},
                                  {{"attributes", attributes}, {"indices", strip}, {"mode", 5}}}}}});
  doc["nodes"] = json::array(
      {{{"name", "parent"}, {"matrix", {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 1, 2, 3, 1}}, {"children", {1}}},
       {{"name", "child"},
        {"mesh", 0},
        {"rotation", {0, 0.70710678, 0, 0.70710678}},
        {"scale", {1, 2, 1}},
        {"translation", {0, 0, -1}}}});
  doc["scenes"] = json::array({{{"nodes", {0}}}});
  doc["scene"] = 0;
  doc["materials"] = json::array({{{"name", "plain"},
                                   {"emissiveFactor", {0.1, 0.2, 0.3}},
                                   {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}}});
  doc["buffers"] = json::array(
      {{{"byteLength", b.bytes().size()}, {"uri", "data:application/octet-stream;base64," + base64(b.bytes())}}});
  return doc.dump(1);
}

}  // namespace test::gltf_fuzz

namespace {

// --- regressions (inputs the fuzzer found, minimized)
// ----------------------------------------------------------------------

// A node whose world matrix is not singular but nearly so (scale 1e-11 on every axis: det 1e-33) was imported
// as an instance, and validateScene() then rejected the built scene ("degenerate (zero-scale) transform").
// Found by a numeric-token mutation of the generated .gltf; the importer now skips |det| < 1e-30 too.
TEST_F(GltfFuzz, NearlySingularNodeIsSkipped) {
  json doc = {{"asset", {{"version", "2.0"}}}};
  BinBuilder b(doc);
  const int pos = b.accessor({{"bufferView", b.view(std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0})},
                              {"componentType", kFloat},
                              {"count", 3},
                              {"type", "VEC3"},
                              {"min", {0, 0, 0}},
                              {"max", {1, 1, 0}}});
  doc["meshes"] = json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}}}}}}}});
  doc["nodes"] = json::array({{{"name", "tiny"}, {"mesh", 0}, {"scale", {1e-11, 1e-11, 1e-11}}},
                              {{"name", "plain"}, {"mesh", 0}}});
  doc["scenes"] = json::array({{{"nodes", {0, 1}}}});
  doc["buffers"] = json::array(
      {{{"byteLength", b.bytes().size()}, {"uri", "data:application/octet-stream;base64," + base64(b.bytes())}}});
  const std::string text = doc.dump();
  const fs::path path = dir_ / "tiny.gltf";
  writeFile(path, std::vector<uint8_t>(text.begin(), text.end()));

  GltfImportReport report;
  Result<ImportedScene> scene = importGltfScene(path.string(), {}, &report);
  ASSERT_TRUE(scene) << scene.error().message;
  ASSERT_EQ(scene->instances.size(), 1u);
  EXPECT_EQ(scene->instances[0].node, 1);
  EXPECT_TRUE(std::any_of(report.warnings.begin(), report.warnings.end(),
                          [](const std::string& w) { return w.find("singular") != std::string::npos; }));
  Result<Scene> built = buildImportedScene(*scene);
  ASSERT_TRUE(built) << built.error().message;
  const Status valid = validateScene(*built);
  EXPECT_TRUE(valid) << valid.error().message;
}

}  // namespace
}  // namespace visbuf
