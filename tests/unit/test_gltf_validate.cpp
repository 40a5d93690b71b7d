// Tests for the schema check that runs before tinygltf parses a glTF document (engine/asset/gltf_validate.cpp):
// every rule of the table broken in several ways gives MalformedInput naming the JSON path; the issue's examples
// (wide integers that tinygltf would wrap, negative indices, numbers written as strings) are refused end to end
// with hand-written paths; extras are not looked at; a valid value of every rule passes.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gltf_doc_builder.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/gltf_validate.h"

namespace visbuf {
namespace {

using gltf_detail::GltfRule;
using nlohmann::json;
using test::DocBuilder;
using test::GltfImportTest;
using test::kTriangle;
using test::triangleMesh;

// A pattern as a JSON pointer to one concrete instance: "[]" -> element 0, "{}" -> key "K", "[#0]" -> element 0.
std::string pointerOf(const std::string& pattern) {
  std::string out = "/";
  for (size_t i = 0; i < pattern.size(); ++i) {
    if (pattern.compare(i, 4, "[#0]") == 0) {
      out += "/0";
      i += 3;
    } else if (pattern.compare(i, 2, "[]") == 0) {
      out += "/0";
      ++i;
    } else if (pattern.compare(i, 2, "{}") == 0) {
      out += "/K";
      ++i;
    } else if (pattern[i] == '.') {
      out += '/';
    } else {
      out += pattern[i];
    }
  }
  return out;
}
// The same instance as the messages write it: "nodes[0].children[0]", "...attributes.K".
std::string pathOf(const std::string& pattern) {
  std::string out;
  for (size_t i = 0; i < pattern.size(); ++i) {
    if (pattern.compare(i, 2, "[]") == 0) {
      out += "[0]";
      ++i;
    } else if (pattern.compare(i, 2, "{}") == 0) {
      out += ".K";
      ++i;
    } else {
      out += pattern[i];
    }
  }
  return out;
}

// A document holding `value` at the rule's first instance; for an Index rule, its collection has one entry.
json docWith(const GltfRule& rule, const json& value) {
  json doc = json::object();
  if (rule.kind == GltfRule::Kind::Index) doc[json::json_pointer(pointerOf(rule.collection) + "/0")] = json::object();
  doc[json::json_pointer(pointerOf(rule.pattern))] = value;
  return doc;
}

json goodValue(const GltfRule& rule) {
  switch (rule.kind) {
    case GltfRule::Kind::Index: return 0;
    case GltfRule::Kind::Integer: return rule.min;
    case GltfRule::Kind::Stride: return 8;
    case GltfRule::Kind::Enum: return rule.values.back();
    case GltfRule::Kind::TextEnum: return rule.names.back();
    case GltfRule::Kind::Text: return "text";
    case GltfRule::Kind::Boolean: return false;
    case GltfRule::Kind::Number: return rule.low == -HUGE_VAL ? -2.5 : rule.low + 0.25;
    case GltfRule::Kind::Numbers: return json(std::vector<double>(static_cast<size_t>(rule.min), 0.25));
    case GltfRule::Kind::Object: return json::object();
  }
  return nullptr;
}

// Values each rule must refuse: wide integers (2^32 + a valid value, as tinygltf's narrowing would read it
// back as valid), negative, strings holding numbers, fractions, and other JSON types.
std::vector<json> badValues(const GltfRule& rule) {
  const int64_t k2p32 = int64_t{1} << 32;
  switch (rule.kind) {
    case GltfRule::Kind::Index:
      return {k2p32, -1, "0", 0.5, 1.0, 1, json::array({0}), nullptr, json::parse("18446744073709551616")};
    case GltfRule::Kind::Integer: {
      std::vector<json> out = {rule.max + 1, json::parse("18446744073709551616"), "1", 1.5, json::object(), true,
                               json::parse("1e300")};
      out.push_back(rule.min - 1);
      return out;
    }
    case GltfRule::Kind::Stride: return {k2p32 + 8, 2, 6, 256, -4, "8"};
    case GltfRule::Kind::Enum: return {k2p32 + rule.values[0], -1, std::to_string(rule.values[0]), 7};
    case GltfRule::Kind::TextEnum: return {"no such value", 3, json::array({rule.names[0]})};
    case GltfRule::Kind::Text: return {3, json::object(), json::array()};
    case GltfRule::Kind::Boolean: return {"true", 1};
    case GltfRule::Kind::Number: {
      std::vector<json> out = {"NaN", "0", nullptr, json::array({1}), json::object(), true};
      if (rule.low != -HUGE_VAL) out.push_back(rule.low - 0.5);  // a negative factor
      if (rule.high != HUGE_VAL) out.push_back(rule.high + 0.5);
      return out;
    }
    case GltfRule::Kind::Object: return {1, "{}", json::array(), nullptr};
    case GltfRule::Kind::Numbers: {
      std::vector<json> out;
      json strings(std::vector<double>(static_cast<size_t>(rule.min), 1.0));
      strings.back() = "NaN";
      out.push_back(strings);
      json nested(std::vector<double>(static_cast<size_t>(rule.min), 1.0));
      nested.front() = json::array({1.0});
      out.push_back(nested);
      out.push_back(json::object({{"x", 1}}));
      out.push_back(1.0);
      out.push_back(json(std::vector<double>(static_cast<size_t>(rule.min - 1), 1.0)));
      if (rule.max < (int64_t{1} << 53)) out.push_back(json(std::vector<double>(static_cast<size_t>(rule.max + 1), 1.0)));
      for (double outside : {rule.low - 0.5, rule.high + 0.5}) {  // an element beyond a bounded factor's range
        if (!std::isfinite(outside)) continue;
        json ranged(std::vector<double>(static_cast<size_t>(rule.min), 0.5));
        ranged.back() = outside;
        out.push_back(ranged);
      }
      return out;
    }
  }
  return {};
}

TEST(GltfValidate, EveryRuleAcceptsAValidValue) {
  ASSERT_GT(gltf_detail::gltfValidationRules().size(), 150u);
  for (const GltfRule& rule : gltf_detail::gltfValidationRules()) {
    const json doc = docWith(rule, goodValue(rule));
    Status s = gltf_detail::validateGltfDocument(doc, "f.gltf");
    EXPECT_TRUE(s.ok()) << rule.pattern << ": " << s.error().message << "\n" << doc.dump();
  }
}

TEST(GltfValidate, EveryRuleRefusesBadValuesNamingThePath) {
  for (const GltfRule& rule : gltf_detail::gltfValidationRules()) {
    for (const json& bad : badValues(rule)) {
      const json doc = docWith(rule, bad);
      Status s = gltf_detail::validateGltfDocument(doc, "f.gltf");
      ASSERT_FALSE(s.ok()) << rule.pattern << " accepted " << bad.dump();
      EXPECT_EQ(s.error().code, ErrorCode::MalformedInput);
      const std::string prefix = "f.gltf: " + pathOf(rule.pattern);
      EXPECT_EQ(s.error().message.rfind(prefix, 0), 0u)
          << rule.pattern << " = " << bad.dump() << ": " << s.error().message;
    }
  }
}

// An object or array on the way to a checked property must have that type.
TEST(GltfValidate, ContainersOfTheWrongType) {
  struct Case {
    const char* doc;
    const char* message;
  };
  const Case cases[] = {
      {R"({"nodes": {"0": {}}})", "f.gltf: nodes: expected an array, found an object"},
      {R"({"nodes": [3]})", "f.gltf: nodes[0]: expected an object, found an integer"},
      {R"({"meshes": [{"primitives": [{"attributes": [0]}]}]})",
       "f.gltf: meshes[0].primitives[0].attributes: expected an object, found an array"},
      {R"({"accessors": [{"sparse": "yes"}]})", "f.gltf: accessors[0].sparse: expected an object, found a string"},
      {R"({"nodes": [{"extensions": []}]})", "f.gltf: nodes[0].extensions: expected an object, found an array"},
  };
  for (const Case& c : cases) {
    Status s = gltf_detail::validateGltfDocument(json::parse(c.doc), "f.gltf");
    ASSERT_FALSE(s.ok()) << c.doc;
    EXPECT_EQ(s.error().message, c.message);
  }
}

// ---------------------------------------------------------------------------------------------------------
// End to end, through importGltfMesh: the issue's examples, with the paths written out by hand.

class GltfValidateImport : public GltfImportTest {
 protected:
  json base() {
    DocBuilder b;
    const int pos = b.addVec3(kTriangle);
    const int idx = b.addIndices16({0, 1, 2});
    json doc = b.build(triangleMesh(pos, idx), {{{"mesh", 0}, {"children", {1}}}, json::object()});
    doc["materials"] = json::array({json::object()});
    return doc;
  }
  void expectRefused(const json& doc, const std::string& message) {
    auto mesh = importGltfMesh(write("doc.gltf", doc));
    ASSERT_FALSE(mesh.ok()) << "accepted: " << message;
    EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
    EXPECT_NE(mesh.error().message.find("doc.gltf: " + message), std::string::npos) << mesh.error().message;
  }
};

TEST_F(GltfValidateImport, BaseDocumentImports) {
  auto mesh = importGltfMesh(write("doc.gltf", base()));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->indices.size(), 3u);
}

TEST_F(GltfValidateImport, WideIntegersThatWouldWrap) {
  json doc = base();
  doc["nodes"][0]["children"][0] = uint64_t{4294967297};  // tinygltf: node 1
  expectRefused(doc, "nodes[0].children[0]: 4294967297 is not a valid index; nodes has 2 entries");
  doc = base();
  doc["meshes"][0]["primitives"][0]["mode"] = uint64_t{4294967300};  // tinygltf: 4 (TRIANGLES)
  expectRefused(doc, "meshes[0].primitives[0].mode: 4294967300 is not one of 0, 1, 2, 3, 4, 5, 6");
  doc = base();
  doc["accessors"][0]["componentType"] = uint64_t{4294972422};  // 5126 + 2^32
  expectRefused(doc, "accessors[0].componentType: 4294972422 is not one of");
  doc = base();
  doc["accessors"][0]["sparse"] = {{"count", 1},
                                   {"indices", {{"bufferView", 1}, {"componentType", 5123}}},
                                   {"values", {{"bufferView", 0}, {"byteOffset", uint64_t{1} << 62}}}};
  expectRefused(doc, "accessors[0].sparse.values.byteOffset: 4611686018427387904 is not a valid byte offset");
  doc = base();
  doc["scenes"][0]["nodes"][0] = json::parse("18446744073709551616");  // beyond uint64: a float in JSON
  expectRefused(doc, "scenes[0].nodes[0]: 1.8446744073709552e+19 is not a valid index (not an integer)");
}

TEST_F(GltfValidateImport, NegativeIndicesAndOffsets) {
  json doc = base();
  doc["accessors"][0]["bufferView"] = -1;
  expectRefused(doc, "accessors[0].bufferView: -1 is not a valid index; bufferViews has 2 entries");
  doc = base();
  doc["accessors"][1]["byteOffset"] = -4;
  expectRefused(doc, "accessors[1].byteOffset: -4 is not a valid byte offset");
  doc = base();
  doc["meshes"][0]["primitives"][0]["material"] = -1;
  expectRefused(doc, "meshes[0].primitives[0].material: -1 is not a valid index; materials has 1 entry");
  doc = base();
  doc["bufferViews"][0]["byteLength"] = -12;
  expectRefused(doc, "bufferViews[0].byteLength: -12 is not a valid byte length");
}

TEST_F(GltfValidateImport, NumbersThatAreNotNumbers) {
  json doc = base();
  doc["nodes"][0]["translation"] = json::array({"NaN", 0, 0});
  expectRefused(doc, "nodes[0].translation[0]: \"NaN\" is not a number");
  doc = base();
  doc["nodes"][1]["scale"] = json::object({{"x", 1}});
  expectRefused(doc, "nodes[1].scale: expected an array of numbers, found an object");
  doc = base();
  doc["nodes"][0]["matrix"] = std::vector<double>(15, 1.0);
  expectRefused(doc, "nodes[0].matrix: has 15 elements, expected 16");
  doc = base();
  doc["materials"][0]["pbrMetallicRoughness"] = {{"baseColorFactor", {1, 1, 1, "1"}}};
  expectRefused(doc, "materials[0].pbrMetallicRoughness.baseColorFactor[3]: \"1\" is not a number");
  doc = base();
  doc["materials"][0]["emissiveTexture"] = {
      {"index", 0}, {"extensions", {{"KHR_texture_transform", {{"rotation", "0.5"}}}}}};
  doc["textures"] = json::array({json::object()});
  expectRefused(doc, "materials[0].emissiveTexture.extensions.KHR_texture_transform.rotation: \"0.5\" is not a number");
}

TEST_F(GltfValidateImport, ExtrasAreFreeForm) {
  json doc = base();
  doc["nodes"][0]["extras"] = {{"translation", "x"}, {"mesh", -1}, {"children", {4294967296}}};
  doc["extras"] = {{"nodes", "not an array"}};
  auto mesh = importGltfMesh(write("doc.gltf", doc));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
}

// ---------------------------------------------------------------------------------------------------------
// Inputs that are not glTF: recognised by their first bytes, whatever their name.

TEST_F(GltfValidateImport, NotAGltfFile) {
  struct Case {
    const char* name;
    std::string bytes;
    const char* message;
  };
  const Case cases[] = {
      {"cube.obj", "# Blender\nv 0 0 0\nv 1 0 0\nf 1 2 3\n", "cube.obj: not a glTF file (text that looks like"},
      {"mesh.gltf", "v 0 0 0\n", "mesh.gltf: not a glTF file"},
      {"image.gltf", std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16), "image.gltf: not a glTF file (it is a PNG image)"},
      {"photo.glb", std::string("\xff\xd8\xff\xe0\0\x10JFIF", 10), "photo.glb: not a glTF file (it is a JPEG image)"},
      {"empty.gltf", "", "empty.gltf: not a glTF file (the file is empty)"},
      {"blank.gltf", " \n\t ", "blank.gltf: not a glTF file (only white space"},
      {"array.gltf", "[1, 2, 3]", "array.gltf: not a glTF file (a JSON array, not an object"},
      {"scene.gltf", std::string("VBPK\x05\0\0\0", 8), "scene.gltf: is a visbuf pack, not a glTF file; use render --scene"},
  };
  for (const Case& c : cases) {
    auto mesh = importGltfMesh(writeText(c.name, c.bytes));
    ASSERT_FALSE(mesh.ok()) << c.name;
    EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput) << c.name;
    EXPECT_NE(mesh.error().message.find(c.message), std::string::npos) << mesh.error().message;
    EXPECT_EQ(mesh.error().message.find("parse"), std::string::npos) << mesh.error().message;
  }
  // A JSON object with a UTF-8 byte order mark is still glTF text (the parser then judges it).
  auto bom = importGltfMesh(writeText("bom.gltf", "\xef\xbb\xbf{\"asset\": {\"version\": \"2.0\"}}"));
  if (!bom.ok()) {
    EXPECT_EQ(bom.error().message.find("not a glTF file"), std::string::npos) << bom.error().message;
  }
}

}  // namespace
}  // namespace visbuf
