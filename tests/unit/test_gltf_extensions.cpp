// The extension audit (gltf_extensions.h): the table is sorted and searchable; a required extension visbuf does
// not read, known or not, is refused by name before the parser; a used one that is not fully read gives exactly
// one warning naming it and what is dropped, wherever the file uses it (declared or not); metadata and read
// extensions stay silent; --ignore-required-extension imports the file with the warning.
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "gltf_doc_builder.h"
#include "visbuf/asset/gltf_extensions.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf {
namespace {

using nlohmann::json;

size_t countContaining(const std::vector<std::string>& lines, const std::string& what) {
  size_t n = 0;
  for (const std::string& l : lines) n += l.find(what) != std::string::npos;
  return n;
}

class ExtensionAuditTest : public test::TempDirTest {
 protected:
  // A one-triangle file; `patch` is merged into the document (extensions lists, material extensions, ...).
  Result<ImportedScene> import(const json& patch, GltfImportReport* report, const GltfImportOptions& options = {}) {
    test::DocBuilder b;
    const int pos = b.addVec3(test::kTriangle);
    json meshes = test::triangleMesh(pos);
    meshes[0]["primitives"][0]["material"] = 0;
    json doc = b.build(meshes, json::array({{{"mesh", 0}}}));
    doc["materials"] = json::array({json::object()});
    doc.merge_patch(patch);
    const std::string path = (dir_ / "ext.gltf").string();
    std::ofstream(path) << doc.dump();
    return importGltfScene(path, options, report);
  }
};

}  // namespace

TEST(GltfExtensionTable, SortedUniqueAndFound) {
  const auto table = gltfExtensions();
  ASSERT_FALSE(table.empty());
  for (size_t i = 1; i < table.size(); ++i) EXPECT_LT(table[i - 1].name, table[i].name) << table[i].name;
  for (const GltfExtension& e : table) {
    EXPECT_EQ(findGltfExtension(e.name), &e);
    // A row says what visbuf does, or what is lost, or both (Partial); the warnings quote them.
    EXPECT_EQ(e.effect.empty(), e.support == GltfExtensionSupport::Dropped) << e.name;
    EXPECT_EQ(e.dropped.empty(), e.support == GltfExtensionSupport::Read) << e.name;
  }
  EXPECT_EQ(findGltfExtension("KHR_not_an_extension"), nullptr);
  EXPECT_EQ(findGltfExtension(""), nullptr);
}

TEST_F(ExtensionAuditTest, RequiredNotReadIsRefusedByName) {
  for (const char* name : {"KHR_materials_sheen", "VENDOR_made_up_extension"}) {
    SCOPED_TRACE(name);
    Result<ImportedScene> s = import({{"extensionsUsed", {name}}, {"extensionsRequired", {name}}}, nullptr);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.error().code, ErrorCode::Unsupported);
    EXPECT_NE(s.error().message.find(std::string("required extension '") + name + "' is not supported"),
              std::string::npos)
        << s.error().message;
    EXPECT_NE(s.error().message.find("--ignore-required-extension"), std::string::npos) << s.error().message;
  }
}

TEST_F(ExtensionAuditTest, RequiredReadImports) {
  GltfImportReport report;
  Result<ImportedScene> s =
      import({{"extensionsUsed", {"KHR_texture_transform"}}, {"extensionsRequired", {"KHR_texture_transform"}}},
             &report);
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(countContaining(report.warnings, "extension"), 0u);
}

TEST_F(ExtensionAuditTest, UsedNotReadWarnsOnceWhereverItIsMet) {
  GltfImportReport report;
  // Declared, and met on two materials and a node: one warning. Undeclared but met: one warning too.
  json materials = json::array({{{"extensions", {{"KHR_materials_sheen", {{"sheenColorFactor", {1, 0, 0}}}}}}},
                                {{"extensions", {{"KHR_materials_sheen", json::object()}}}}});
  Result<ImportedScene> s = import({{"extensionsUsed", {"KHR_materials_sheen", "KHR_xmp_json_ld"}},
                                    {"materials", materials},
                                    {"extensions", {{"VENDOR_secret", json::object()}}}},
                                   &report);
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(countContaining(report.warnings, "'KHR_materials_sheen' is not supported; dropped: the sheen layer"), 1u);
  EXPECT_EQ(countContaining(report.warnings, "'VENDOR_secret' (/extensions) is unknown to visbuf and ignored"), 1u);
  EXPECT_EQ(countContaining(report.warnings, "KHR_xmp_json_ld"), 0u);  // metadata: silent
}

TEST_F(ExtensionAuditTest, IgnoredRequiredImportsWithTheWarning) {
  for (const char* ignore : {"KHR_materials_sheen", "*"}) {
    SCOPED_TRACE(ignore);
    GltfImportOptions options;
    options.ignoreRequiredExtensions = {ignore};
    GltfImportReport report;
    Result<ImportedScene> s = import(
        {{"extensionsUsed", {"KHR_materials_sheen"}}, {"extensionsRequired", {"KHR_materials_sheen"}}}, &report,
        options);
    ASSERT_TRUE(s.ok()) << s.error().message;
    EXPECT_EQ(countContaining(report.warnings, "'KHR_materials_sheen' is not supported"), 1u);
  }
}

TEST_F(ExtensionAuditTest, NamesAreEscapedInMessages) {
  GltfImportReport report;
  Result<ImportedScene> s = import({{"extensionsUsed", {"EVIL_\x1b[2J"}}}, &report);
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(countContaining(report.warnings, "EVIL_"), 1u);
  EXPECT_EQ(countContaining(report.warnings, "\x1b"), 0u);
}

}  // namespace visbuf
