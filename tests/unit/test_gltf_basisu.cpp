// KHR_texture_basisu: a texture whose KTX2 (Basis Universal) image sits in the extension uses its plain `source`
// fallback when it has one (one warning: the extension is read in part); without a fallback the texture is also
// dropped with a warning that names the extension and the texture. A file that requires the extension is refused
// by name (visbuf does not decode KTX2) unless the caller ignores it (GltfImportOptions::ignoreRequiredExtensions).
#include <cstring>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "temp_dir_test.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf {
namespace {

class BasisuTest : public test::TempDirTest {
 protected:
  // A triangle with a material whose base colour uses texture 0; `texture` is that texture's JSON. Image 0 is a
  // PNG file name, image 1 a KTX2 one (neither is opened by the import).
  Result<ImportedScene> import(const nlohmann::json& texture, bool required, GltfImportReport* report,
                               const GltfImportOptions& options = {}) {
    std::vector<uint8_t> bytes(36 + 24);
    const float tri[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1};
    std::memcpy(bytes.data(), tri, sizeof(tri));
    nlohmann::json doc = {
        {"asset", {{"version", "2.0"}}},
        {"extensionsUsed", {"KHR_texture_basisu"}},
        {"buffers", {{{"byteLength", 60}, {"uri", "data:application/octet-stream;base64," + test::base64(bytes)}}}},
        {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}, {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 24}}}},
        {"accessors",
         {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"min", {0, 0, 0}},
           {"max", {1, 1, 0}}},
          {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}}}},
        {"images", {{{"uri", "albedo.png"}}, {{"uri", "albedo.ktx2"}, {"mimeType", "image/ktx2"}}}},
        {"textures", {texture}},
        {"materials", {{{"name", "m"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}}}, {"material", 0}}}}}}},
        {"nodes", {{{"mesh", 0}}}},
        {"scenes", {{{"nodes", {0}}}}}};
    if (required) doc["extensionsRequired"] = {"KHR_texture_basisu"};
    const std::string path = (dir_ / "basisu.gltf").string();
    std::ofstream(path) << doc.dump();
    return importGltfScene(path, options, report);
  }
  static bool warnedAbout(const GltfImportReport& r, const std::string& what) {
    for (const std::string& w : r.warnings)
      if (w.find(what) != std::string::npos) return true;
    return false;
  }
};

}  // namespace

TEST_F(BasisuTest, FallbackSourceIsUsed) {
  GltfImportReport report;
  Result<ImportedScene> s =
      import({{"source", 0}, {"extensions", {{"KHR_texture_basisu", {{"source", 1}}}}}}, false, &report);
  ASSERT_TRUE(s.ok()) << s.error().message;
  const TextureRef& ref = s->materials.at(0).baseColorTexture;
  EXPECT_EQ(ref.texture, 0);
  EXPECT_EQ(ref.image, 0);
  EXPECT_EQ(ref.uri, "albedo.png");
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_TRUE(warnedAbout(report, "extension 'KHR_texture_basisu' is read in part: the texture's fallback PNG/JPEG "
                                  "source is used"))
      << report.warnings[0];
}

TEST_F(BasisuTest, RequiredIsRefusedByNameUnlessIgnored) {
  const nlohmann::json texture = {{"source", 0}, {"extensions", {{"KHR_texture_basisu", {{"source", 1}}}}}};
  Result<ImportedScene> refused = import(texture, true, nullptr);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::Unsupported);
  EXPECT_NE(refused.error().message.find("required extension 'KHR_texture_basisu' is not supported"),
            std::string::npos)
      << refused.error().message;
  GltfImportOptions options;
  options.ignoreRequiredExtensions = {"KHR_texture_basisu"};
  GltfImportReport report;
  Result<ImportedScene> s = import(texture, true, &report, options);
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(s->materials.at(0).baseColorTexture.image, 0);
  EXPECT_TRUE(warnedAbout(report, "extension 'KHR_texture_basisu' is read in part"));
}

TEST_F(BasisuTest, NoFallbackWarnsNamingTheExtension) {
  GltfImportOptions ignore;
  ignore.ignoreRequiredExtensions = {"*"};
  for (bool required : {false, true}) {
    SCOPED_TRACE(required);
    GltfImportReport report;
    Result<ImportedScene> s = import({{"name", "albedoTex"}, {"extensions", {{"KHR_texture_basisu", {{"source", 1}}}}}},
                                     required, &report, ignore);
    ASSERT_TRUE(s.ok()) << s.error().message;
    const TextureRef& ref = s->materials.at(0).baseColorTexture;
    EXPECT_EQ(ref.image, -1);
    EXPECT_TRUE(warnedAbout(report, "baseColorTexture: texture 0 'albedoTex' has only a KHR_texture_basisu (KTX2 / "
                                    "Basis Universal) image, which is not supported, and no fallback `source`"))
        << (report.warnings.empty() ? std::string("no warnings") : report.warnings[0]);
    EXPECT_FALSE(warnedAbout(report, "no usable image source"));
  }
  // A texture without either keeps the generic warning.
  GltfImportReport report;
  Result<ImportedScene> s = import(nlohmann::json::object(), false, &report);
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_TRUE(warnedAbout(report, "texture 0 has no usable image source"));
}

}  // namespace visbuf
