// Untrusted assets (docs/security.md), the engine side: the URI rule for external references
// (asset/uri_resolver.h), regular-file-only non-blocking reads with a size budget (core/file_read.h), the
// image pixel budget read from the header, truncated images as errors, the import's memory budget, and the
// importer's refusals (glTF 1.0, node cycles anywhere, coordinates that overflow bounds). The hand-made files
// of tests/data/hostile are used where they fit; tests/cli_hostile.py runs `visbuf bake` on all of them.
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../build_config.h"
#include "temp_dir_test.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/texture_bake.h"
#include "visbuf/asset/uri_resolver.h"
#include "visbuf/core/file_read.h"
#include "visbuf/core/image_io.h"

namespace visbuf {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

const std::string kCanary = "S3cr3t!Bytes";  // 12 bytes: 3 RGBA8 vertex colours

// From the build's definition, not __FILE__ (a compiler cache or a relative build may make __FILE__ relative to
// the build folder, which is not where the tests run).
fs::path hostileDir() { return fs::path(VISBUF_TEST_DATA_DIR) / "hostile"; }

std::vector<uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

// A one-triangle glTF whose COLOR_0 (3 x unorm8 VEC4 = 12 bytes) comes from an external buffer at `uri`.
json colorBufferDoc(const std::string& uri, uint64_t byteLength = 12) {
  const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::vector<uint8_t> raw(sizeof pos);
  std::memcpy(raw.data(), pos, sizeof pos);
  return {{"asset", {{"version", "2.0"}}},
          {"scene", 0},
          {"scenes", {{{"nodes", {0}}}}},
          {"nodes", {{{"mesh", 0}}}},
          {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"COLOR_0", 1}}}}}}}}},
          {"buffers",
           {{{"byteLength", 36}, {"uri", "data:application/octet-stream;base64," + test::base64(raw)}},
            {{"byteLength", byteLength}, {"uri", uri}}}},
          {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}, {{"buffer", 1}, {"byteLength", 12}}}},
          {"accessors",
           {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"},
             {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
            {{"bufferView", 1}, {"componentType", 5121}, {"normalized", true}, {"count", 3}, {"type", "VEC4"}}}}};
}

// The same triangle with a material whose base colour texture is the image at `uri`.
json imageDoc(const std::string& uri) {
  json doc = colorBufferDoc("unused.bin");
  doc["buffers"].erase(1);
  doc["bufferViews"].erase(1);
  doc["accessors"].erase(1);
  doc["meshes"][0]["primitives"][0]["attributes"].erase("COLOR_0");
  doc["meshes"][0]["primitives"][0]["material"] = 0;
  doc["images"] = {{{"uri", uri}}};
  doc["textures"] = {{{"source", 0}}};
  doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
  return doc;
}

class HostileAssets : public test::TempDirTest {
 protected:
  // dir_/asset/NAME holds the glTF; dir_/canary.bin is outside its folder.
  fs::path asset(const std::string& name, const json& doc) {
    const fs::path path = dir_ / "asset" / name;
    writeText(path, doc.dump(1));
    return path;
  }
  void placeCanary(const std::string& bytes) { writeText(dir_ / "canary.bin", bytes); }
  std::string importError(const fs::path& path, const GltfImportOptions& options = {}) {
    Result<MeshSource> mesh = importGltfMesh(path.string(), options);
    EXPECT_FALSE(mesh);
    return mesh ? std::string() : mesh.error().message;
  }
};

// --- the URI rule ------------------------------------------------------------------------------------------

TEST(HostileUri, PercentDecodingIsRfc3986) {
  EXPECT_EQ(percentDecodeUri("colour%20map.png"), "colour map.png");
  EXPECT_EQ(percentDecodeUri("%2e%2E%2fx"), "../x");
  EXPECT_EQ(percentDecodeUri("a+b%zz%4"), "a+b%zz%4");  // '+' is not a space; malformed escapes stay
  EXPECT_TRUE(isDataUri("DATA:application/octet-stream;base64,AAAA"));
  EXPECT_FALSE(isDataUri("dat"));
  EXPECT_EQ(quoteForMessage("a\x1b[31mb\nc'\\"), "a\\x1b[31mb\\nc\\'\\\\");
  EXPECT_EQ(quoteForMessage("\xc2\x9b" "1m"), "\\xc2\\x9b1m");  // C1 control (CSI) escaped
  EXPECT_EQ(quoteForMessage("caf\xc3\xa9"), "caf\xc3\xa9");      // other UTF-8 kept
}

TEST_F(HostileAssets, ResolverKeepsEverythingInsideTheFolder) {
  const fs::path folder = dir_ / "asset";
  fs::create_directories(folder / "sub");
  writeText(folder / "a.bin", "a");
  writeText(dir_ / "secret.bin", "secret");
  Result<UriResolver> r = UriResolver::create((folder / "x.gltf").string());
  ASSERT_TRUE(r) << r.error().message;
  const std::string canonicalFolder = fs::canonical(folder).string();
  for (const std::string uri : {"a.bin", "./a.bin", "sub/../a.bin", "sub/..%2Fa.bin", "%61.bin"}) {
    Result<std::string> p = r->resolve(uri, "t");
    ASSERT_TRUE(p) << uri << ": " << p.error().message;
    EXPECT_EQ(*p, canonicalFolder + "/a.bin") << uri;
  }
  Result<std::string> missing = r->resolve("missing/file.bin", "t");  // may not exist
  ASSERT_TRUE(missing);
  EXPECT_EQ(*missing, canonicalFolder + "/missing/file.bin");
  EXPECT_TRUE(r->resolve(canonicalFolder + "/a.bin", "t"));  // absolute, but inside

  for (const std::string uri : {"../secret.bin", "..%2Fsecret.bin", "%2E%2E%2Fsecret.bin", "sub/../../secret.bin",
                                "/etc/passwd", "%2Fetc%2Fpasswd", "..", "../asset2/x.bin"}) {
    Result<std::string> p = r->resolve(uri, "t");
    ASSERT_FALSE(p) << uri << " -> " << *p;
    EXPECT_EQ(p.error().code, ErrorCode::MalformedInput);
    EXPECT_EQ(p.error().message, "t: uri '" + uri +
                                     "' resolves outside the asset's folder and the allowed roots; refused (only "
                                     "files inside the asset's folder are read; see --allow-uri-root)");
  }
  for (const std::string uri : {"file:///etc/passwd", "http://example.com/a.bin", "C:/x.bin"}) {
    Result<std::string> p = r->resolve(uri, "t");
    ASSERT_FALSE(p) << uri;
    EXPECT_TRUE(contains(p.error().message, "has a URI scheme")) << p.error().message;
  }
  EXPECT_TRUE(contains(r->resolve("a%00.bin", "t").error().message, "NUL byte"));
  EXPECT_TRUE(contains(r->resolve("", "t").error().message, "is empty"));
}

TEST_F(HostileAssets, ResolverFollowsSymlinksAndJudgesTheTarget) {
  const fs::path folder = dir_ / "asset";
  fs::create_directories(folder / "real");
  writeText(folder / "real" / "in.bin", "in");
  writeText(dir_ / "secret.bin", "secret");
  fs::create_symlink("real/in.bin", folder / "inside.bin");             // inside -> inside: fine
  fs::create_symlink("../secret.bin", folder / "out.bin");              // file link out
  fs::create_symlink("..", folder / "up");                              // folder link out
  fs::create_symlink(dir_ / "nowhere.bin", folder / "dangling.bin");    // dangling, outside
  fs::create_symlink("loop2", folder / "loop1");
  fs::create_symlink("loop1", folder / "loop2");
  Result<UriResolver> r = UriResolver::create((folder / "x.gltf").string());
  ASSERT_TRUE(r);
  Result<std::string> in = r->resolve("inside.bin", "t");
  ASSERT_TRUE(in) << in.error().message;
  EXPECT_EQ(*in, fs::canonical(folder / "real" / "in.bin").string());
  for (const std::string uri : {"out.bin", "up/secret.bin", "up/asset/../secret.bin", "dangling.bin"}) {
    Result<std::string> p = r->resolve(uri, "t");
    ASSERT_FALSE(p) << uri << " -> " << *p;
    EXPECT_TRUE(contains(p.error().message, "resolves outside the asset's folder")) << p.error().message;
  }
  // Through the folder link and back in: still inside.
  EXPECT_TRUE(r->resolve("up/asset/real/in.bin", "t"));
  EXPECT_TRUE(contains(r->resolve("loop1", "t").error().message, "too many symbolic links"));
}

// The message must not tell whether the target exists, nor its size: the same text either way.
TEST_F(HostileAssets, TraversalMessageIsTheSameWhetherOrNotTheTargetExists) {
  fs::create_directories(dir_ / "asset");
  fs::create_symlink("../canary.bin", dir_ / "asset" / "link.bin");
  for (const std::string& uri :
       std::vector<std::string>{"../canary.bin", "..%2Fcanary.bin", (dir_ / "canary.bin").string(), "link.bin"}) {
    SCOPED_TRACE(uri);
    const fs::path path = asset("t.gltf", colorBufferDoc(uri));
    placeCanary(kCanary);
    const std::string present = importError(path);
    placeCanary(kCanary + std::string(500, 'x'));  // the size a size-mismatch message would print
    const std::string resized = importError(path);
    fs::remove(dir_ / "canary.bin");
    const std::string absent = importError(path);
    EXPECT_TRUE(contains(present, "buffer 1: uri '" + uri + "' resolves outside the asset's folder")) << present;
    EXPECT_EQ(present, resized);
    EXPECT_EQ(present, absent);
    // (the size, not digits of the random temporary folder's name, which an absolute uri puts in the message)
    std::string withoutFolder = present;
    for (size_t at; (at = withoutFolder.find(dir_.string())) != std::string::npos;)
      withoutFolder.erase(at, dir_.string().size());
    EXPECT_FALSE(contains(withoutFolder, "512")) << present;
    EXPECT_FALSE(contains(present, kCanary)) << present;
  }
}

// A GLB's JSON chunk names external files by the same rule.
TEST_F(HostileAssets, GlbExternalBuffersFollowTheRule) {
  placeCanary(kCanary);
  std::string jsonText = colorBufferDoc("..%2Fcanary.bin").dump();
  while (jsonText.size() % 4) jsonText += ' ';
  std::string glb(12, '\0');
  auto put32 = [&](std::string& out, size_t at, uint32_t v) { std::memcpy(out.data() + at, &v, 4); };
  put32(glb, 0, 0x46546C67);  // "glTF"
  put32(glb, 4, 2);
  put32(glb, 8, uint32_t(12 + 8 + jsonText.size()));
  std::string chunk(8, '\0');
  put32(chunk, 0, uint32_t(jsonText.size()));
  put32(chunk, 4, 0x4E4F534A);  // "JSON"
  glb += chunk + jsonText;
  writeText(dir_ / "asset" / "t.glb", glb);
  const std::string error = importError(dir_ / "asset" / "t.glb");
  EXPECT_TRUE(contains(error, "buffer 1: uri '..%2Fcanary.bin' resolves outside the asset's folder")) << error;
  GltfImportOptions options;
  options.allowedUriRoots = {dir_.string()};
  EXPECT_TRUE(importGltfMesh((dir_ / "asset" / "t.glb").string(), options));
}

TEST_F(HostileAssets, AllowedRootsWidenTheRule) {
  placeCanary(kCanary);
  const fs::path path = asset("t.gltf", colorBufferDoc("../canary.bin"));
  EXPECT_TRUE(contains(importError(path), "resolves outside"));
  GltfImportOptions options;
  options.allowedUriRoots = {dir_.string()};
  Result<MeshSource> mesh = importGltfMesh(path.string(), options);
  ASSERT_TRUE(mesh) << mesh.error().message;
  ASSERT_EQ(mesh->colors.size(), 3u);
  EXPECT_EQ(std::memcmp(mesh->colors.data(), kCanary.data(), 12), 0);  // read, as explicitly allowed
  options.allowedUriRoots = {(dir_ / "no such folder").string()};
  Result<MeshSource> bad = importGltfMesh(path.string(), options);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().code, ErrorCode::InvalidArgument);
  EXPECT_TRUE(contains(bad.error().message, "not an existing folder")) << bad.error().message;
}

TEST_F(HostileAssets, ImageUrisFollowTheSameRule) {
  writeText(dir_ / "canary.png", "not even a png");
  for (const std::string& uri :
       std::vector<std::string>{"../canary.png", "%2E%2E%2Fcanary.png", (dir_ / "canary.png").string()}) {
    Result<ImportedScene> s = importGltfScene(asset("img.gltf", imageDoc(uri)).string());
    ASSERT_FALSE(s) << uri;
    EXPECT_EQ(s.error().code, ErrorCode::MalformedInput);
    EXPECT_TRUE(contains(s.error().message, "image 0: uri '" + uri + "' resolves outside")) << s.error().message;
  }
  // Inside (a subfolder, percent-encoded): resolved to the canonical path, not opened by the import.
  Result<ImportedScene> ok = importGltfScene(asset("img.gltf", imageDoc("tex/a%20b.png")).string());
  ASSERT_TRUE(ok) << ok.error().message;
  ASSERT_EQ(ok->images.size(), 1u);
  EXPECT_EQ(ok->images[0].path, (fs::canonical(dir_ / "asset") / "tex" / "a b.png").string());
}

// --- regular files only, never blocking ---------------------------------------------------------------------

TEST_F(HostileAssets, FifosAndFoldersAreRefusedWithoutBlocking) {
  fs::create_directories(dir_ / "asset");
  const fs::path fifo = dir_ / "asset" / "fifo.gltf";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir_ / "asset" / "fifo.bin").c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();

  EXPECT_EQ(probeFile(fifo.string()), FileKind::Fifo);
  Result<std::vector<uint8_t>> read = readRegularFile(fifo.string());
  ASSERT_FALSE(read);
  EXPECT_EQ(read.error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(read.error().message, fifo.string() + ": not a regular file (a FIFO); only regular files are read");

  Result<MeshSource> mesh = importGltfMesh(fifo.string());
  ASSERT_FALSE(mesh);
  EXPECT_TRUE(contains(mesh.error().message, "not a regular file (a FIFO)")) << mesh.error().message;
  Result<MeshSource> folder = importGltfMesh((dir_ / "asset").string());
  ASSERT_FALSE(folder);
  EXPECT_TRUE(contains(folder.error().message, "not a regular file (a directory)")) << folder.error().message;

  Result<MeshSource> buffer = importGltfMesh(asset("t.gltf", colorBufferDoc("fifo.bin")).string());
  ASSERT_FALSE(buffer);
  EXPECT_EQ(buffer.error().code, ErrorCode::InvalidArgument);
  EXPECT_TRUE(contains(buffer.error().message, "buffer 1: uri 'fifo.bin': not a regular file (a FIFO)"))
      << buffer.error().message;

  EXPECT_FALSE(isPackFile(fifo.string()));
  Result<Scene> pack = readPack(fifo.string());
  ASSERT_FALSE(pack);
  EXPECT_TRUE(contains(pack.error().message, "not a regular file (a FIFO)")) << pack.error().message;

  ImportedScene imported;
  imported.name = "fifo";
  ImportedImage image;
  image.name = "fifo.png";
  image.path = (dir_ / "asset" / "fifo.bin").string();
  imported.images.push_back(image);
  Material m;
  m.baseColorTexture.image = 0;
  Scene scene;
  scene.materials.push_back(m);
  Status baked = bakeTextures(imported, {}, &scene);
  ASSERT_FALSE(baked);
  EXPECT_TRUE(contains(baked.error().message, "is not a regular file (a FIFO)")) << baked.error().message;

  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));  // nothing waited for a writer
}

TEST_F(HostileAssets, FileReadsKeepToTheirBudget) {
  writeText(dir_ / "f.bin", std::string(100, 'a'));
  FileReadOptions options;
  options.maxBytes = 99;
  Result<std::vector<uint8_t>> big = readRegularFile((dir_ / "f.bin").string(), options);
  ASSERT_FALSE(big);
  EXPECT_EQ(big.error().code, ErrorCode::CapacityExceeded);
  EXPECT_TRUE(contains(big.error().message, "100 bytes exceeds the read budget of 99 bytes")) << big.error().message;
  options.maxBytes = 100;
  EXPECT_EQ(readRegularFile((dir_ / "f.bin").string(), options)->size(), 100u);
  EXPECT_EQ(readFilePrefix((dir_ / "f.bin").string(), 4)->size(), 4u);
  Result<std::vector<uint8_t>> missing = readRegularFile((dir_ / "none").string());
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::FileNotFound);
  fs::create_symlink("f.bin", dir_ / "link.bin");
  options.noFollow = true;
  EXPECT_FALSE(readRegularFile((dir_ / "link.bin").string(), options));
  EXPECT_EQ(probeFile((dir_ / "link.bin").string(), nullptr, true), FileKind::Symlink);
}

// --- budgets ------------------------------------------------------------------------------------------------

TEST_F(HostileAssets, ImportMemoryBudgetIsCheckedBeforeAllocating) {
  writeText(dir_ / "asset" / "colors.bin", kCanary);
  const fs::path path = asset("t.gltf", colorBufferDoc("colors.bin"));
  ASSERT_TRUE(importGltfMesh(path.string()));
  GltfImportOptions options;
  options.maxMemoryBytes = 64;  // less than the file itself
  Result<MeshSource> small = importGltfMesh(path.string(), options);
  ASSERT_FALSE(small);
  EXPECT_EQ(small.error().code, ErrorCode::CapacityExceeded);
  EXPECT_TRUE(contains(small.error().message, "past the import memory budget of 64 bytes")) << small.error().message;
  // Room for the file, its parsed JSON (estimated at 8 bytes a byte), the 36 + 12 buffer bytes and 16 more:
  // the mesh's decoded and emitted vertices are refused before its first accessor is decoded.
  options.maxMemoryBytes = fs::file_size(path) * 9 + 36 + 12 + 16;
  Result<MeshSource> tight = importGltfMesh(path.string(), options);
  ASSERT_FALSE(tight);
  EXPECT_EQ(tight.error().code, ErrorCode::CapacityExceeded);
  EXPECT_TRUE(contains(tight.error().message, "mesh 0: its 1 primitives need about")) << tight.error().message;
}

TEST_F(HostileAssets, ImageBombIsRefusedFromItsHeader) {
  SKIP_WITHOUT_OIIO();
  const std::vector<uint8_t> bomb = readBytes(hostileDir() / "image_bomb.png");
  ASSERT_GT(bomb.size(), 1000u);
  ASSERT_LT(bomb.size(), 100000u);  // small in the repository, 268 Mpixel once decoded
  const auto start = std::chrono::steady_clock::now();
  Result<LinearImage> image = decodeImage(bomb.data(), bomb.size(), "bomb", ColorSpace::Srgb);
  ASSERT_FALSE(image);
  EXPECT_EQ(image.error().code, ErrorCode::CapacityExceeded);
  EXPECT_EQ(image.error().message, "bomb: 16384x16384 = 268435456 pixels exceeds the image pixel budget of "
                                   "67108864 (raise it with --max-image-pixels)");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));  // the header only
  // The budget is an option; the whole bake honours it.
  Result<ImportedScene> imported = importGltfScene((hostileDir() / "image_bomb.gltf").string());
  ASSERT_TRUE(imported) << imported.error().message;
  Scene scene;
  scene.materials = imported->materials;
  TextureBakeOptions options;
  Status s = bakeTextures(*imported, options, &scene);
  ASSERT_FALSE(s);
  EXPECT_TRUE(contains(s.error().message, "268435456 pixels exceeds")) << s.error().message;
  options.maxImagePixels = 0;
  EXPECT_EQ(bakeTextures(*imported, options, &scene).error().code, ErrorCode::InvalidArgument);
  const std::vector<uint8_t> rgba(8 * 8 * 4, 200);
  ASSERT_TRUE(writeRgba8Image((dir_ / "small.png").string(), 8, 8, rgba));
  const std::vector<uint8_t> small = readBytes(dir_ / "small.png");
  EXPECT_TRUE(decodeImage(small.data(), small.size(), "small", ColorSpace::Linear, 64));
  Result<LinearImage> over = decodeImage(small.data(), small.size(), "small", ColorSpace::Linear, 63);
  ASSERT_FALSE(over);
  EXPECT_TRUE(contains(over.error().message, "8x8 = 64 pixels exceeds the image pixel budget of 63"));
}

TEST_F(HostileAssets, TruncatedImagesAreErrors) {
  SKIP_WITHOUT_OIIO();
  const std::vector<uint8_t> jpeg = readBytes(hostileDir() / "truncated.jpg");
  ASSERT_FALSE(jpeg.empty());
  Result<LinearImage> image = decodeImage(jpeg.data(), jpeg.size(), "cut.jpg", ColorSpace::Srgb);
  ASSERT_FALSE(image) << "a truncated JPEG decoded (half grey)";
  EXPECT_EQ(image.error().code, ErrorCode::MalformedInput);
  EXPECT_TRUE(contains(image.error().message, "cut.jpg: truncated or corrupt image")) << image.error().message;
  EXPECT_TRUE(contains(image.error().message, "Premature end of JPEG file")) << image.error().message;
  // A PNG cut in its IDAT.
  const std::vector<uint8_t> rgba(64 * 64 * 4, 77);
  std::vector<uint8_t> varied = rgba;
  for (size_t i = 0; i < varied.size(); ++i) varied[i] = uint8_t(i * 7919 % 251);
  ASSERT_TRUE(writeRgba8Image((dir_ / "p.png").string(), 64, 64, varied));
  std::vector<uint8_t> png = readBytes(dir_ / "p.png");
  ASSERT_TRUE(decodeImage(png.data(), png.size(), "p.png", ColorSpace::Linear));
  png.resize(png.size() / 2);
  Result<LinearImage> cut = decodeImage(png.data(), png.size(), "p.png", ColorSpace::Linear);
  ASSERT_FALSE(cut);
  EXPECT_EQ(cut.error().code, ErrorCode::MalformedInput);
}

// --- import checks ------------------------------------------------------------------------------------------

TEST_F(HostileAssets, OnlyGltf2IsImported) {
  Result<MeshSource> v1 = importGltfMesh((hostileDir() / "version_1_0.gltf").string());
  ASSERT_FALSE(v1);
  EXPECT_EQ(v1.error().code, ErrorCode::Unsupported);
  EXPECT_TRUE(contains(v1.error().message, "asset.version '1.0' is not supported (only glTF 2.x)"))
      << v1.error().message;
  writeText(dir_ / "asset" / "colors.bin", kCanary);
  json doc = colorBufferDoc("colors.bin");
  for (const std::string version : {"2.0", "2.1", "2"}) {
    doc["asset"]["version"] = version;
    EXPECT_TRUE(importGltfMesh(asset("v.gltf", doc).string())) << version;
  }
  for (const std::string version : {"3.0", "1.0", "2.x", "", "20"}) {
    doc["asset"]["version"] = version;
    EXPECT_FALSE(importGltfMesh(asset("v.gltf", doc).string())) << version;
  }
  doc["asset"]["version"] = "2.0";
  doc["asset"]["minVersion"] = "2.1";
  Result<MeshSource> min = importGltfMesh(asset("v.gltf", doc).string());
  ASSERT_FALSE(min);
  EXPECT_TRUE(contains(min.error().message, "asset.minVersion '2.1' is not supported")) << min.error().message;
  // The version is checked before any external file is looked at.
  doc = colorBufferDoc("../canary.bin");
  doc["asset"]["version"] = "1.0";
  EXPECT_EQ(importGltfMesh(asset("v.gltf", doc).string()).error().code, ErrorCode::Unsupported);
}

TEST_F(HostileAssets, NodeCyclesAnywhereAreRefused) {
  for (const auto& import : {+[](const std::string& p) { return importGltfMesh(p).ok() ? std::string() :
                                                                   importGltfMesh(p).error().message; },
                             +[](const std::string& p) { return importGltfScene(p).ok() ? std::string() :
                                                                   importGltfScene(p).error().message; }}) {
    EXPECT_TRUE(contains(import((hostileDir() / "node_cycle.gltf").string()),
                         "node 1 'a' is its own ancestor (the node graph has a cycle)"));
    writeText(dir_ / "asset" / "colors.bin", kCanary);
    json doc = colorBufferDoc("colors.bin");
    doc["nodes"].push_back({{"children", {2}}});  // node 1 -> 2 -> 2: a self-loop outside the scene
    doc["nodes"].push_back({{"children", {2}}});
    EXPECT_TRUE(contains(import(asset("self.gltf", doc).string()), "node 2 is its own child"));
    doc["nodes"][2]["children"] = json::array();
    doc["nodes"].push_back({{"children", {2}}});  // nodes 1 and 3 both claim node 2
    EXPECT_TRUE(contains(import(asset("parents.gltf", doc).string()), "node 2 has several parents (nodes 1 and 3)"));
  }
}

TEST_F(HostileAssets, CoordinatesThatOverflowBoundsAreRefused) {
  Result<MeshSource> huge = importGltfMesh((hostileDir() / "huge_positions.gltf").string());
  ASSERT_FALSE(huge);
  EXPECT_EQ(huge.error().code, ErrorCode::MalformedInput);
  EXPECT_TRUE(contains(huge.error().message, "vertex 1 at (3e+38, 0, 0) is too far from the origin")) << huge.error().message;
  Result<ImportedScene> hugeScene = importGltfScene((hostileDir() / "huge_positions.gltf").string());
  ASSERT_FALSE(hugeScene);
  EXPECT_TRUE(contains(hugeScene.error().message, "too far from the origin")) << hugeScene.error().message;
  // A unit triangle scaled far out by its node: the instance's world bounds are refused in scene import too.
  writeText(dir_ / "asset" / "colors.bin", kCanary);
  json doc = colorBufferDoc("colors.bin");
  doc["nodes"][0]["scale"] = {1e30, 1e30, 1e30};
  Result<ImportedScene> scaled = importGltfScene(asset("scaled.gltf", doc).string());
  ASSERT_FALSE(scaled);
  EXPECT_TRUE(contains(scaled.error().message, "world-space bounds")) << scaled.error().message;
  EXPECT_FALSE(importGltfMesh(asset("scaled.gltf", doc).string()));
  doc["nodes"][0]["scale"] = {1e6, 1e6, 1e6};  // far but fine
  EXPECT_TRUE(importGltfScene(asset("scaled.gltf", doc).string()));
}

TEST(HostileFiles, TheCommittedFilesAreSmall) {
  uint64_t total = 0;
  for (const auto& entry : fs::directory_iterator(hostileDir())) total += entry.file_size();
  EXPECT_LT(total, 200u * 1024u);
}

}  // namespace
}  // namespace visbuf
