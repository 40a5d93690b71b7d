// EXT_mesh_gpu_instancing import: a gltfpack-style file with 4096 instances against the equivalent expanded file
// (one node per instance; tests/unit/instancing_fixture.h), through both entry points; attribute subsets and
// component types; extensionsRequired; the errors of malformed instance data. The GPU render comparison of the
// two files is tests/gpu/test_instancing.cpp.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <random>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>

#include "instancing_fixture.h"
#include "skin8_fixture.h"
#include "temp_dir_test.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"

namespace visbuf {
namespace {

// A buffer holding `bytes` as a data: URI.
nlohmann::json dataBuffer(const std::vector<uint8_t>& bytes) {
  return {{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(bytes)}};
}

class InstancingTest : public test::TempDirTest {
 protected:
  std::string write(const nlohmann::json& doc, const std::string& name) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << doc.dump();
    return path;
  }
  // Imports both files of `files` as scenes and expects the same meshes and the same instances, transforms
  // equal to the bit (both compose the same double-precision T * R * S after the same parent transform).
  void expectSameScene(const test::InstancingFiles& files, size_t instances) {
    GltfImportReport report;
    Result<ImportedScene> a = importGltfScene(write(files.instanced, "instanced.gltf"), {}, &report);
    ASSERT_TRUE(a.ok()) << a.error().message;
    for (const std::string& w : report.warnings) ADD_FAILURE() << "unexpected warning: " << w;
    Result<ImportedScene> b = importGltfScene(write(files.expanded, "expanded.gltf"));
    ASSERT_TRUE(b.ok()) << b.error().message;
    ASSERT_EQ(a->instances.size(), instances);
    ASSERT_EQ(b->instances.size(), instances);
    ASSERT_EQ(a->meshes.size(), b->meshes.size());
    for (size_t m = 0; m < a->meshes.size(); ++m) {
      EXPECT_EQ(a->meshes[m].source.positions, b->meshes[m].source.positions);
      EXPECT_EQ(a->meshes[m].source.indices, b->meshes[m].source.indices);
      EXPECT_EQ(a->meshes[m].mirrored, b->meshes[m].mirrored);
    }
    size_t different = 0;
    for (size_t i = 0; i < instances; ++i) {
      const ImportedInstance& x = a->instances[i];
      const ImportedInstance& y = b->instances[i];
      EXPECT_EQ(x.mesh, y.mesh);
      EXPECT_EQ(x.material, y.material);
      EXPECT_EQ(x.node, 1) << "every instance comes from the instanced node";
      different += x.transform != y.transform;
    }
    EXPECT_EQ(different, 0u) << "instance transforms differ from the expanded nodes'";
  }
};

}  // namespace

// 4096 instances (TRANSLATION float, ROTATION normalized short, SCALE float) under a parent with its own
// transform: the same meshes and instances, transform for transform, as the file with one node per instance;
// the flattened mesh (importGltfMesh) has the same vertices too.
TEST_F(InstancingTest, GltfpackStyleFileEqualsExpandedNodes) {
  const test::InstancingFiles files = test::makeInstancingFiles({.instances = 4096});
  expectSameScene(files, 4096);
  Result<MeshSource> a = importGltfMesh(write(files.instanced, "instanced_mesh.gltf"));
  Result<MeshSource> b = importGltfMesh(write(files.expanded, "expanded_mesh.gltf"));
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->positions.size(), 4096u * 6);
  EXPECT_EQ(a->positions, b->positions);
  EXPECT_EQ(a->normals, b->normals);
  EXPECT_EQ(a->indices, b->indices);
  // The instances really are where the extension puts them: instance 1 is the parent's transform applied to
  // translation (3, 0, 0) + its rotated, scaled octahedron; its centre (the mean of the 6 vertices) is
  // parent * (3, 0, 0).
  Result<ImportedScene> s = importGltfScene(write(files.instanced, "instanced.gltf"));
  ASSERT_TRUE(s.ok());
  const glm::dvec3 centre(s->instances[1].transform * glm::dvec4(0.0, 0.0, 0.0, 1.0));
  const double c = std::cos(0.5), sn = std::sin(0.5);
  const glm::dvec3 expected = glm::dvec3(10.0, -2.0, 4.0) + 1.5 * glm::dvec3(3.0 * c, 0.0, -3.0 * sn);
  EXPECT_LT(glm::length(centre - expected), 1e-12);
}

// Any subset of the three attributes, and every component type the extension lists for ROTATION (float,
// normalized byte, normalized short; TRANSLATION and SCALE are float only); extensionsRequired names the
// extension (supported: the file imports).
TEST_F(InstancingTest, AttributeSubsetsAndTypes) {
  struct Case {
    test::InstancingOptions options;
    const char* what;
  };
  const Case cases[] = {
      {{.instances = 64, .rotation = false, .scale = false}, "TRANSLATION only"},
      {{.instances = 64, .translation = false, .scale = false}, "ROTATION only"},
      {{.instances = 64, .translation = false, .rotation = false}, "SCALE only"},
      {{.instances = 64, .scale = false, .rotationComponentType = 5120}, "TRANSLATION + ROTATION (byte)"},
      {{.instances = 64, .rotationComponentType = 5126, .required = true}, "all three, float rotation, required"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    expectSameScene(test::makeInstancingFiles(c.options), c.options.instances);
  }
}

// Malformed instance data: every error names the node, the extension and the accessor.
TEST_F(InstancingTest, MalformedInstancesAreRefused) {
  const test::InstancingFiles files = test::makeInstancingFiles({.instances = 16});
  auto ext = [](nlohmann::json& doc) -> nlohmann::json& {
    return doc["nodes"][1]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
  };
  auto importFails = [&](const nlohmann::json& doc, const std::string& message) {
    Result<ImportedScene> s = importGltfScene(write(doc, "bad.gltf"));
    ASSERT_FALSE(s.ok()) << message;
    EXPECT_EQ(s.error().code, ErrorCode::MalformedInput);
    EXPECT_NE(s.error().message.find("node 1 'instanced' EXT_mesh_gpu_instancing"), std::string::npos)
        << s.error().message;
    EXPECT_NE(s.error().message.find(message), std::string::npos) << s.error().message;
  };
  {  // counts differ
    nlohmann::json doc = files.instanced;
    doc["accessors"][ext(doc)["SCALE"].get<int>()]["count"] = 15;
    importFails(doc, "(SCALE): count 15 differs from accessor");
  }
  {  // non-finite translation: the TRANSLATION accessor pointed at data whose instance 3 has a NaN x
    nlohmann::json doc = files.instanced;
    const int t = ext(doc)["TRANSLATION"].get<int>();
    std::vector<uint8_t> nan(12 * 16, 0);
    const float qnan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(nan.data() + 12 * 3, &qnan, 4);
    doc["buffers"].push_back(dataBuffer(nan));
    doc["bufferViews"].push_back({{"buffer", 1}, {"byteLength", nan.size()}});
    doc["accessors"][t]["bufferView"] = doc["bufferViews"].size() - 1;
    importFails(doc, "(TRANSLATION): instance 3 has a non-finite value");
  }
  {  // unnormalized integer rotation: not in the extension's table
    nlohmann::json doc = files.instanced;
    doc["accessors"][ext(doc)["ROTATION"].get<int>()].erase("normalized");
    importFails(doc, "(ROTATION): unsupported format (SHORT, 4 components); expected VEC4 of FLOAT or normalized");
  }
  {  // wrong type
    nlohmann::json doc = files.instanced;
    doc["accessors"][ext(doc)["TRANSLATION"].get<int>()]["type"] = "VEC2";
    importFails(doc, "(TRANSLATION): unsupported format (FLOAT, 2 components); expected VEC3 of FLOAT");
  }
  {  // a normalized integer SCALE: the extension's table has FLOAT only (ROTATION alone may be quantised)
    nlohmann::json doc = files.instanced;
    nlohmann::json quantised = doc["accessors"][ext(doc)["ROTATION"].get<int>()];  // over the rotation shorts
    quantised["type"] = "VEC3";
    doc["accessors"].push_back(quantised);
    ext(doc)["SCALE"] = doc["accessors"].size() - 1;
    importFails(doc, "(SCALE): unsupported format (SHORT normalized, 3 components); expected VEC3 of FLOAT");
  }
  {  // zero quaternion
    nlohmann::json doc = files.instanced;
    std::vector<uint8_t> zero(8 * 16, 0);
    doc["buffers"].push_back(dataBuffer(zero));
    doc["bufferViews"].push_back({{"buffer", 1}, {"byteLength", zero.size()}});
    doc["accessors"][ext(doc)["ROTATION"].get<int>()]["bufferView"] = doc["bufferViews"].size() - 1;
    importFails(doc, "(ROTATION): instance 0 has a zero-length rotation quaternion");
  }
  // Indices and JSON types: refused before parsing, naming the JSON path (gltf_validate.h).
  auto schemaFails = [&](const nlohmann::json& doc, const std::string& message) {
    Result<ImportedScene> s = importGltfScene(write(doc, "bad.gltf"));
    ASSERT_FALSE(s.ok()) << message;
    EXPECT_EQ(s.error().code, ErrorCode::MalformedInput);
    EXPECT_NE(s.error().message.find(message), std::string::npos) << s.error().message;
  };
  {  // accessor that does not exist
    nlohmann::json doc = files.instanced;
    ext(doc)["SCALE"] = 99;
    schemaFails(doc, "bad.gltf: nodes[1].extensions.EXT_mesh_gpu_instancing.attributes.SCALE: 99 is not a valid index");
  }
  {  // an instanced node whose mesh does not exist
    nlohmann::json doc = files.instanced;
    doc["nodes"][1]["mesh"] = 7;
    schemaFails(doc, "bad.gltf: nodes[1].mesh: 7 is not a valid index; meshes has 1 entry");
  }
  {  // attributes not an object
    nlohmann::json doc = files.instanced;
    doc["nodes"][1]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = 3;
    schemaFails(doc, "bad.gltf: nodes[1].extensions.EXT_mesh_gpu_instancing.attributes: expected an object, found an integer");
  }
}

// extensionsRequired: a required extension the importer does not know is refused (Unsupported, naming it);
// EXT_mesh_gpu_instancing on a skinned or animated node cannot be expressed (its skin carries the node's
// transform): the plain node is imported with a warning, or Unsupported when the file requires the extension.
TEST_F(InstancingTest, RequiredExtensionsAndFallbacks) {
  const test::InstancingFiles files = test::makeInstancingFiles({.instances = 8});
  {
    nlohmann::json doc = files.instanced;
    doc["extensionsRequired"] = {"EXT_mesh_gpu_instancing", "EXT_not_a_real_extension"};
    Result<ImportedScene> s = importGltfScene(write(doc, "unknown.gltf"));
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.error().code, ErrorCode::Unsupported);
    EXPECT_NE(s.error().message.find("required extension 'EXT_not_a_real_extension' is not supported"),
              std::string::npos)
        << s.error().message;
  }
  // An animated instanced node: a translation channel on node 1.
  nlohmann::json doc = files.instanced;
  const std::vector<float> keys = {0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f};
  std::vector<uint8_t> bytes(keys.size() * 4);
  std::memcpy(bytes.data(), keys.data(), bytes.size());
  doc["buffers"].push_back(dataBuffer(bytes));
  doc["bufferViews"].push_back({{"buffer", 1}, {"byteLength", 8}});
  doc["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 8}, {"byteLength", 24}});
  const size_t views = doc["bufferViews"].size();
  doc["accessors"].push_back({{"bufferView", views - 2}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"},
                              {"min", {0.0}}, {"max", {1.0}}});
  doc["accessors"].push_back({{"bufferView", views - 1}, {"componentType", 5126}, {"count", 2}, {"type", "VEC3"}});
  const size_t accessors = doc["accessors"].size();
  nlohmann::json sampler = {{"input", accessors - 2}, {"output", accessors - 1}};
  nlohmann::json channel = {{"sampler", 0}, {"target", {{"node", 1}, {"path", "translation"}}}};
  nlohmann::json animation = {{"samplers", nlohmann::json::array({sampler})},
                              {"channels", nlohmann::json::array({channel})}};
  doc["animations"] = nlohmann::json::array({animation});
  GltfImportReport report;
  Result<ImportedScene> s = importGltfScene(write(doc, "animated.gltf"), {}, &report);
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(s->instances.size(), 1u);
  bool warned = false;
  for (const std::string& w : report.warnings)
    warned = warned || w.find("instancing a skinned or animated node is not supported") != std::string::npos;
  EXPECT_TRUE(warned);
  doc["extensionsRequired"] = {"EXT_mesh_gpu_instancing"};
  Result<ImportedScene> required = importGltfScene(write(doc, "animated_required.gltf"));
  ASSERT_FALSE(required.ok());
  EXPECT_EQ(required.error().code, ErrorCode::Unsupported);
  EXPECT_NE(required.error().message.find("node 1 'instanced' EXT_mesh_gpu_instancing"), std::string::npos)
      << required.error().message;
}

}  // namespace visbuf

namespace visbuf {

// Bounded mutation of the new inputs (instancing attributes, JOINTS_1 / WEIGHTS_1, spot / directional lights):
// a fixed seed, 600 files, each with 1 to 3 of its JSON numbers replaced by a hostile value (out-of-range
// indices and counts, negative, huge, non-integral, overflowing to Inf); every import must return, ok or an
// Error with a message (scripts/test.sh runs the unit tests under ASan / UBSan too, where an out-of-bounds read
// fails). The broader GltfFuzz covers the rest of the importer.
TEST_F(InstancingTest, MutatedExtensionDataNeverCrashes) {
  nlohmann::json lights = test::makeInstancingFiles({.instances = 4}).instanced;
  lights["extensionsUsed"].push_back("KHR_lights_punctual");
  lights["extensions"] = {
      {"KHR_lights_punctual",
       {{"lights",
         {{{"type", "spot"}, {"intensity", 5.0}, {"range", 9.0}, {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.4}}}},
          {{"type", "directional"}, {"intensity", 2.0}}}}}}};
  lights["nodes"][0]["extensions"] = {{"KHR_lights_punctual", {{"light", 0}}}};
  lights["nodes"].push_back({{"rotation", {0.0, 0.0, 0.0, 1.0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
  lights["scenes"][0]["nodes"].push_back(2);
  const std::string seeds[] = {test::makeInstancingFiles({.instances = 16}).instanced.dump(),
                               test::makeSkin8Fixture().doc.dump(), lights.dump()};
  const char* hostile[] = {"-1", "0", "1", "2", "3", "7", "65535", "4294967296", "1e30", "-1e30", "1e400", "0.5", "-0.5",
                           "3.2", "1.5707963267948966", "1.6"};
  std::mt19937 rng(20261125);
  size_t ok = 0, rejected = 0;
  for (int i = 0; i < 600; ++i) {
    std::string text = seeds[size_t(i) % 3];
    // Numbers outside the data: URI (whose base64 holds no JSON numbers worth mutating).
    std::vector<std::pair<size_t, size_t>> numbers;
    for (size_t p = 0; p < text.size();) {
      const bool start = (std::isdigit(static_cast<unsigned char>(text[p])) || text[p] == '-') &&
                         p > 0 && (text[p - 1] == ':' || text[p - 1] == '[' || text[p - 1] == ',');
      if (!start) {
        ++p;
        continue;
      }
      size_t e = p + 1;
      while (e < text.size() && (std::isdigit(static_cast<unsigned char>(text[e])) || std::strchr(".eE+-", text[e]))) ++e;
      numbers.emplace_back(p, e - p);
      p = e;
    }
    ASSERT_FALSE(numbers.empty());
    const int edits = 1 + int(rng() % 3);
    std::vector<std::pair<size_t, size_t>> chosen;
    for (int k = 0; k < edits; ++k) chosen.push_back(numbers[rng() % numbers.size()]);
    std::sort(chosen.begin(), chosen.end(), [](auto a, auto b) { return a.first > b.first; });
    chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
    for (auto [pos, len] : chosen) text.replace(pos, len, hostile[rng() % std::size(hostile)]);
    const std::string path = (dir_ / "mutated.gltf").string();
    std::ofstream(path, std::ios::trunc) << text;
    Result<ImportedScene> s = importGltfScene(path);
    if (s.ok()) {
      ++ok;
      Result<MeshSource> m = importGltfMesh(path);
      if (!m.ok()) {
        EXPECT_FALSE(m.error().message.empty());
      }
    } else {
      ++rejected;
      EXPECT_FALSE(s.error().message.empty());
    }
  }
  std::printf("mutated extension files: %zu imported, %zu rejected with an error\n", ok, rejected);
  EXPECT_GT(ok, 0u);
  EXPECT_GT(rejected, 0u);
}

}  // namespace visbuf
