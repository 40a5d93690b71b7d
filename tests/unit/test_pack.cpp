// Tests for the pack format (engine/asset/pack_{format,writer,reader}.h): round trips of a generated scene
// and of real assets, quantised packs (error bounds and the reported error against a recomputation), the encoded
// geometry streams (decoded with meshoptimizer's own API against the scene; hostile streams), memory-mapped reads,
// truncation, checksums, versions, overflowing counts, atomic writes, and a bounded fuzz run.
#include <gtest/gtest.h>
#include <meshoptimizer.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <glm/gtc/matrix_transform.hpp>
#include <random>
#include <string>
#include <vector>

#include "animation_test_scene.h"
#include "temp_dir_test.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_format.h"
#include "visbuf/asset/pack_geometry.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/generate.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;

using test::assetPath;

// A small scene that exercises every field: two meshes with LOD chains, materials of every alpha mode with
// texture references, mirrored and far-from-origin objects, a non-default camera and anchor, and skinning /
// animation data (the box mesh is skinned, object 1 a skinned object: every optional section is present).
Scene makeTestScene(uint32_t knotSegments = 64, uint32_t knotSides = 12) {
  Scene scene;
  scene.name = "generated test scene";
  Result<Mesh> knot = buildMesh(makeTorusKnot(knotSegments, knotSides));
  Result<Mesh> box = buildMesh(makeBox(2));
  EXPECT_TRUE(knot && box);
  scene.meshes.push_back(std::move(knot.value()));
  scene.meshes.push_back(std::move(box.value()));
  Material opaque;
  opaque.name = "opaque";
  opaque.baseColor = {0.25f, 0.5f, 0.75f, 1.0f};
  Material mask;
  mask.name = "mask";
  mask.alphaMode = AlphaMode::Mask;
  mask.alphaCutoff = 0.3f;
  mask.doubleSided = true;
  mask.baseColorTexture = {2, 5, 1, "textures/leaf.png"};
  Material blend;
  blend.name = "";  // empty names survive too
  blend.alphaMode = AlphaMode::Blend;
  blend.baseColor = {1.0f, 0.0f, 0.0f, 0.25f};
  scene.materials = {opaque, mask, blend};
  scene.objects.push_back({glm::dmat4(1.0), 0, 0});
  scene.objects.push_back(
      {glm::scale(glm::translate(glm::dmat4(1.0), {3.0, 0.0, 0.0}), {-1.0, 2.0, 1.0}), 1, 1});
  scene.objects.push_back({glm::translate(glm::dmat4(1.0), {1e6 + 0.125, -2e5, 3.0}), 0, 2});
  scene.anchor = {1.5, -2.25, 1e5};
  scene.defaultCamera.position = {10.0, 20.0, 30.0};
  scene.defaultCamera.target = {1.0, 2.0, 3.0};
  scene.defaultCamera.fovY = 0.9;
  scene.defaultCamera.nearPlane = 0.01;
  scene.lightDirection = glm::normalize(glm::vec3(-1.0f, 2.0f, 0.5f));
  test::addTestAnimation(scene, 1, 1);
  // Object 2 is moved rigidly by node 1 ("hip") of the first clip, with a phase and a placement.
  scene.rigidObjects.push_back({2, 1, 0, 0.625, glm::translate(glm::dmat4(1.0), {1e6, -2e5, 3.0})});
  return scene;
}

// makeTestScene plus every optional section: tangents (one "none" vertex, both handednesses) and a second uv
// set on the box, and baked textures in two classes (4x4 sRGB with 2 layers, 2x2 linear) that the mask
// material references from its base colour, normal and emissive slots with non-default samplers/transforms.
Scene makeTexturedTestScene() {
  Scene scene = makeTestScene(16, 6);
  Mesh& box = scene.meshes[1];
  box.tangents.assign(box.vertices.size(), glm::vec4(1.0f, 0.0f, 0.0f, 1.0f));
  box.tangents[0] = glm::vec4(0.0f, 1.0f, 0.0f, -1.0f);
  box.tangents[1] = glm::vec4(0.0f);
  for (size_t i = 0; i < box.vertices.size(); ++i) box.uvs1.push_back(glm::vec2(0.5f * float(i), -float(i)));
  auto makeClass = [](uint32_t size, ColorSpace cs, uint32_t layers) {
    TextureClass c;
    c.size = size;
    c.colorSpace = cs;
    c.layers = layers;
    c.mipCount = TextureClass::mipCountFor(size);
    c.texels.resize(c.totalBytes());
    for (size_t i = 0; i < c.texels.size(); ++i) c.texels[i] = uint8_t(i * 7 + size);
    return c;
  };
  scene.textureClasses = {makeClass(4, ColorSpace::Srgb, 2), makeClass(2, ColorSpace::Linear, 1)};
  scene.textures = {{"albedo", 0, ColorSpace::Srgb, 0, 0, 640, 480},
                    {"glow", 3, ColorSpace::Srgb, 0, 1, 4, 4},
                    {"normal", -1, ColorSpace::Linear, 1, 0, 2, 2}};
  Material& m = scene.materials[1];
  m.baseColorTexture.baked = 0;
  m.baseColorTexture.transform = glm::mat3x2(2.0f, -0.5f, 0.25f, 3.0f, 0.125f, -1.0f);
  m.baseColorTexture.sampler = {WrapMode::ClampToEdge, WrapMode::MirroredRepeat, TextureFilter::Nearest,
                                TextureFilter::Linear, MipFilter::None};
  m.normalTexture = {1, 4, 1, "n.png", glm::mat3x2(1.0f), {}, 2};
  m.normalScale = 0.5f;
  m.emissiveTexture.baked = 1;
  m.emissive = {1.0f, 0.5f, 0.0f};
  m.emissiveStrength = 7.0f;
  m.metallic = 0.25f;
  m.roughness = 0.75f;
  m.occlusionStrength = 0.5f;
  return scene;
}

void expectScenesEqual(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.anchor, b.anchor);
  EXPECT_EQ(a.defaultCamera.position, b.defaultCamera.position);
  EXPECT_EQ(a.defaultCamera.target, b.defaultCamera.target);
  EXPECT_EQ(a.defaultCamera.up, b.defaultCamera.up);
  EXPECT_EQ(a.defaultCamera.fovY, b.defaultCamera.fovY);
  EXPECT_EQ(a.defaultCamera.nearPlane, b.defaultCamera.nearPlane);
  EXPECT_EQ(a.lightDirection, b.lightDirection);
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (size_t i = 0; i < a.meshes.size(); ++i) {
    const Mesh& x = a.meshes[i];
    const Mesh& y = b.meshes[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.boundsSphere, y.boundsSphere);
    ASSERT_EQ(x.vertices.size(), y.vertices.size());
    EXPECT_EQ(std::memcmp(x.vertices.data(), y.vertices.data(), x.vertices.size() * sizeof(gpu::Vertex)), 0)
        << "mesh " << i;
    EXPECT_EQ(x.indices, y.indices) << "mesh " << i;
    EXPECT_EQ(x.tangents, y.tangents) << "mesh " << i;
    EXPECT_EQ(x.uvs1, y.uvs1) << "mesh " << i;
    ASSERT_EQ(x.lods.size(), y.lods.size());
    for (size_t l = 0; l < x.lods.size(); ++l) {
      EXPECT_EQ(x.lods[l].firstIndex, y.lods[l].firstIndex);
      EXPECT_EQ(x.lods[l].indexCount, y.lods[l].indexCount);
      EXPECT_EQ(x.lods[l].error, y.lods[l].error);
    }
  }
  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (size_t i = 0; i < a.materials.size(); ++i) {
    const Material& x = a.materials[i];
    const Material& y = b.materials[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.baseColor, y.baseColor);
    EXPECT_EQ(x.alphaMode, y.alphaMode);
    EXPECT_EQ(x.alphaCutoff, y.alphaCutoff);
    EXPECT_EQ(x.doubleSided, y.doubleSided);
    EXPECT_EQ(x.baseColorTexture, y.baseColorTexture);
    EXPECT_EQ(x.metallic, y.metallic);
    EXPECT_EQ(x.roughness, y.roughness);
    EXPECT_EQ(x.normalScale, y.normalScale);
    EXPECT_EQ(x.occlusionStrength, y.occlusionStrength);
    EXPECT_EQ(x.emissive, y.emissive);
    EXPECT_EQ(x.emissiveStrength, y.emissiveStrength);
    for (size_t t = 0; t < kTextureSlotCount; ++t)
      EXPECT_EQ(*textureSlots(x)[t], *textureSlots(y)[t]) << "material " << i << " slot " << t;
  }
  EXPECT_EQ(a.textures, b.textures);
  EXPECT_EQ(a.textureClasses, b.textureClasses);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (size_t i = 0; i < a.objects.size(); ++i) {
    EXPECT_EQ(a.objects[i].transform, b.objects[i].transform) << "object " << i;
    EXPECT_EQ(a.objects[i].mesh, b.objects[i].mesh);
    EXPECT_EQ(a.objects[i].material, b.objects[i].material);
  }
  test::expectAnimationEqual(a, b);
}

std::vector<uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

pack::Header headerOf(const std::vector<uint8_t>& bytes) {
  pack::Header h;
  std::memcpy(&h, bytes.data(), sizeof(h));
  return h;
}

pack::SectionEntry entryOf(const std::vector<uint8_t>& bytes, size_t i) {
  pack::SectionEntry e;
  std::memcpy(&e, bytes.data() + sizeof(pack::Header) + i * sizeof(pack::SectionEntry), sizeof(e));
  return e;
}

void setEntry(std::vector<uint8_t>& bytes, size_t i, const pack::SectionEntry& e) {
  std::memcpy(bytes.data() + sizeof(pack::Header) + i * sizeof(pack::SectionEntry), &e, sizeof(e));
}

size_t sectionIndex(const std::vector<uint8_t>& bytes, const std::string& name) {
  const pack::Header h = headerOf(bytes);
  for (size_t i = 0; i < h.sectionCount; ++i)
    if (std::string(entryOf(bytes, i).name) == name) return i;
  ADD_FAILURE() << "no section " << name;
  return 0;
}

// Recomputes every section checksum that can be computed (section inside the file) and the header checksum,
// so that a deliberate edit reaches the reader's later checks instead of stopping at a checksum mismatch.
void reseal(std::vector<uint8_t>& bytes) {
  if (bytes.size() < sizeof(pack::Header)) return;
  pack::Header h = headerOf(bytes);
  const uint64_t count = std::min<uint64_t>(h.sectionCount, pack::kMaxSections);
  const uint64_t tableEnd = sizeof(pack::Header) + count * sizeof(pack::SectionEntry);
  if (tableEnd > bytes.size()) return;
  for (size_t i = 0; i < count; ++i) {
    pack::SectionEntry e = entryOf(bytes, i);
    if (e.offset <= bytes.size() && e.size <= bytes.size() - e.offset) {
      e.crc32 = pack::crc32(bytes.data() + e.offset, e.size);
      setEntry(bytes, i, e);
    }
  }
  h.headerCrc = 0;
  h.headerCrc = pack::crc32(bytes.data() + sizeof(h), tableEnd - sizeof(h), pack::crc32(&h, sizeof(h)));
  std::memcpy(bytes.data(), &h, sizeof(h));
}

Result<Scene> parse(const std::vector<uint8_t>& bytes) {
  return parsePack(bytes.data(), bytes.size(), "pack.vbp");
}

::testing::AssertionResult failsWith(const Result<Scene>& r, const std::string& text,
                                     ErrorCode code = ErrorCode::MalformedInput) {
  if (r)
    return ::testing::AssertionFailure() << "read succeeded; expected an error containing '" << text << "'";
  if (r.error().code != code)
    return ::testing::AssertionFailure()
           << "code " << errorCodeName(r.error().code) << ": " << r.error().message;
  if (r.error().message.rfind("pack.vbp: ", 0) != 0 || r.error().message.find(text) == std::string::npos)
    return ::testing::AssertionFailure() << "message '" << r.error().message << "' lacks '" << text << "'";
  return ::testing::AssertionSuccess();
}

// --- encoded geometry streams: editing a pack's decoded data
//
// A pack taken apart into its sections and put back together (laid out afresh, checksums recomputed), so a test
// can replace one mesh's encoded stream with one of another length.
struct RawSection {
  pack::SectionEntry entry;
  std::vector<uint8_t> bytes;
};

std::vector<RawSection> splitPack(const std::vector<uint8_t>& bytes) {
  std::vector<RawSection> out;
  for (size_t i = 0; i < headerOf(bytes).sectionCount; ++i) {
    const pack::SectionEntry e = entryOf(bytes, i);
    out.push_back({e, {bytes.begin() + int64_t(e.offset), bytes.begin() + int64_t(e.offset + e.size)}});
  }
  return out;
}

std::vector<uint8_t> joinPack(const std::vector<uint8_t>& original, const std::vector<RawSection>& sections) {
  pack::Header h = headerOf(original);
  h.sectionCount = uint32_t(sections.size());
  uint64_t cursor = (sizeof(pack::Header) + sections.size() * sizeof(pack::SectionEntry) + 15) / 16 * 16;
  std::vector<pack::SectionEntry> table;
  for (const RawSection& r : sections) {
    pack::SectionEntry e = r.entry;
    e.offset = cursor;
    e.size = r.bytes.size();
    e.count = e.elementSize ? e.size / e.elementSize : 0;
    table.push_back(e);
    cursor += (e.size + 15) / 16 * 16;
  }
  h.fileSize = cursor;
  std::vector<uint8_t> out(cursor, 0);
  std::memcpy(out.data(), &h, sizeof(h));
  for (size_t i = 0; i < sections.size(); ++i) {
    setEntry(out, i, table[i]);
    if (!sections[i].bytes.empty())
      std::memcpy(out.data() + table[i].offset, sections[i].bytes.data(), sections[i].bytes.size());
  }
  reseal(out);
  return out;
}

RawSection& rawSection(std::vector<RawSection>& sections, const std::string& name) {
  for (RawSection& r : sections)
    if (std::string(r.entry.name) == name) return r;
  ADD_FAILURE() << "no section " << name;
  return sections.front();
}

// Where a stream's per-mesh byte ranges are recorded: the record section and the byte / length field offsets.
struct StreamLocator {
  const char* records;
  size_t byteField;
  size_t bytesField;
  size_t stride;  // decoded record size (0: indices)
};

StreamLocator locatorOf(const std::string& stream) {
  if (stream == "vertices") return {"meshEncoding", 0, 8, sizeof(gpu::Vertex)};
  if (stream == "qvertices") return {"meshEncoding", 0, 8, sizeof(pack::QVertexRecord)};
  if (stream == "indices") return {"meshEncoding", 16, 24, 0};
  if (stream == "tangents") return {"meshStreams", 0, 8, sizeof(glm::vec4)};
  if (stream == "uvs1") return {"meshStreams", 16, 24, sizeof(glm::vec2)};
  if (stream == "skinVertices") return {"skinnedMeshes", 8, 16, sizeof(SkinVertex)};  // record k: field 'mesh'
  ADD_FAILURE() << "no stream " << stream;
  return {"", 0, 0, 0};
}

template <typename T>
T field(const RawSection& r, size_t record, size_t at) {
  T v;
  std::memcpy(&v, r.bytes.data() + record * r.entry.elementSize + at, sizeof(T));
  return v;
}
template <typename T>
void setField(RawSection& r, size_t record, size_t at, T v) {
  std::memcpy(r.bytes.data() + record * r.entry.elementSize + at, &v, sizeof(T));
}

// Replaces mesh `mesh`'s encoded bytes in `stream` with `encoded`, moving the other meshes' ranges behind it.
void replaceStream(std::vector<RawSection>& sections, const std::string& stream, size_t mesh,
                   const std::vector<uint8_t>& encoded) {
  const StreamLocator loc = locatorOf(stream);
  RawSection& records = rawSection(sections, loc.records);
  RawSection& data = rawSection(sections, stream);
  const uint64_t at = field<uint64_t>(records, mesh, loc.byteField);
  const uint64_t old = field<uint64_t>(records, mesh, loc.bytesField);
  data.bytes.erase(data.bytes.begin() + int64_t(at), data.bytes.begin() + int64_t(at + old));
  data.bytes.insert(data.bytes.begin() + int64_t(at), encoded.begin(), encoded.end());
  for (size_t k = 0; k < records.entry.count; ++k) {
    const uint64_t b = field<uint64_t>(records, k, loc.byteField);
    if (k != mesh && b != pack::kNoStream && b > at) setField<uint64_t>(records, k, loc.byteField, b + encoded.size() - old);
  }
  setField<uint64_t>(records, mesh, loc.bytesField, encoded.size());
}

// Decodes mesh `mesh`'s `stream` (records of T; uint32_t for "indices"), lets `edit` change them, re-encodes them
// and returns the resealed pack: how the tests put bad values into encoded sections.
template <typename T>
std::vector<uint8_t> editDecoded(const std::vector<uint8_t>& bytes, const std::string& stream, size_t mesh,
                                 const std::function<void(std::vector<T>&)>& edit) {
  std::vector<RawSection> sections = splitPack(bytes);
  const StreamLocator loc = locatorOf(stream);
  RawSection& records = rawSection(sections, loc.records);
  const RawSection& data = rawSection(sections, stream);
  const uint64_t at = field<uint64_t>(records, mesh, loc.byteField);
  const uint64_t size = field<uint64_t>(records, mesh, loc.bytesField);
  const RawSection& meshes = rawSection(sections, "meshes");
  // "skinVertices" is located by its skinnedMeshes record, which names the mesh.
  const size_t meshIndex = stream == "skinVertices" ? field<uint32_t>(records, mesh, 0) : mesh;
  const uint32_t vertexCount = field<uint32_t>(meshes, meshIndex, offsetof(pack::MeshRecord, vertexCount));
  const uint32_t indexCount = field<uint32_t>(meshes, meshIndex, offsetof(pack::MeshRecord, indexCount));
  std::vector<T> decoded(loc.stride ? vertexCount : indexCount);
  if (loc.stride) {
    EXPECT_EQ(sizeof(T), loc.stride);
    EXPECT_EQ(pack::decodeVertexStream(decoded.data(), decoded.size(), sizeof(T), data.bytes.data() + at, size), "");
    edit(decoded);
    replaceStream(sections, stream, mesh, pack::encodeVertexStream(decoded.data(), decoded.size(), sizeof(T)));
  } else {
    const uint32_t codec = field<uint32_t>(records, mesh, offsetof(pack::MeshEncodingRecord, indexCodec));
    std::vector<uint32_t> indices(indexCount);
    EXPECT_EQ(pack::decodeIndexStream(indices.data(), indices.size(), codec, data.bytes.data() + at, size), "");
    std::memcpy(decoded.data(), indices.data(), indices.size() * sizeof(uint32_t));
    edit(decoded);
    std::memcpy(indices.data(), decoded.data(), indices.size() * sizeof(uint32_t));
    const pack::EncodedIndices e = pack::encodeIndexStream(indices.data(), indices.size());
    replaceStream(sections, stream, mesh, e.bytes);
    setField<uint32_t>(rawSection(sections, "meshEncoding"), mesh, offsetof(pack::MeshEncodingRecord, indexCodec),
                       e.codec);
  }
  return joinPack(bytes, sections);
}

class PackFileTest : public test::TempDirTest {
 protected:
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
};

TEST(PackFormat, Crc32MatchesTheStandardCheckValue) {
  EXPECT_EQ(pack::crc32("123456789", 9), 0xCBF43926u);  // the CRC-32/ISO-HDLC check value (zlib, PNG)
  EXPECT_EQ(pack::crc32("56789", 5, pack::crc32("1234", 4)), 0xCBF43926u);
  EXPECT_EQ(pack::crc32("", 0), 0u);
}

// --- round trips
// --------------------------------------------------------------------------------------------

TEST(PackRoundTrip, GeneratedSceneInMemory) {
  const Scene scene = makeTestScene();
  PackWriteReport report;
  Result<std::vector<uint8_t>> bytes = serializePack(scene, &report);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(report.fileBytes, bytes->size());
  EXPECT_EQ(bytes->size() % pack::kAlignment, 0u);
  for (const PackSectionInfo& s : report.sections) EXPECT_EQ(s.offset % pack::kAlignment, 0u) << s.name;
  Result<Scene> back = parse(*bytes);
  ASSERT_TRUE(back) << back.error().message;
  expectScenesEqual(scene, *back);
  // The layout is deterministic: serialising the result again gives the same bytes.
  Result<std::vector<uint8_t>> again = serializePack(*back);
  ASSERT_TRUE(again);
  EXPECT_EQ(*again, *bytes);
}

TEST(PackRoundTrip, TexturedSceneInMemory) {
  const Scene scene = makeTexturedTestScene();
  PackWriteReport report;
  Result<std::vector<uint8_t>> bytes = serializePack(scene, &report);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(report.sections.size(), 15u + 16u);  // 9 required, meshStreams, tangents, uvs1, 3 texture, 16 animation
  Result<Scene> back = parse(*bytes);
  ASSERT_TRUE(back) << back.error().message;
  expectScenesEqual(scene, *back);
  Result<std::vector<uint8_t>> again = serializePack(*back);
  ASSERT_TRUE(again);
  EXPECT_EQ(*again, *bytes);
  // A texture class starts 16-aligned in "texels"; the second one after the first one's bytes.
  const pack::SectionEntry classes = entryOf(*bytes, sectionIndex(*bytes, "textureClasses"));
  pack::TextureClassRecord second;
  std::memcpy(&second, bytes->data() + classes.offset + sizeof(second), sizeof(second));
  EXPECT_EQ(second.firstByte, (scene.textureClasses[0].texels.size() + 15) / 16 * 16);
  // The writer refuses inconsistent texture data.
  Scene broken = scene;
  broken.textureClasses[1].texels.pop_back();
  EXPECT_FALSE(serializePack(broken));
  broken = scene;
  broken.materials[1].baseColorTexture.baked = 2;  // a linear texture in the sRGB base colour slot
  EXPECT_FALSE(serializePack(broken));
}

TEST_F(PackFileTest, GeneratedSceneThroughFile) {
  const Scene scene = makeTestScene();
  const fs::path path = dir_ / "scene.vbp";
  ASSERT_TRUE(writePack(scene, path.string()));
  EXPECT_TRUE(isPackFile(path.string()));
  Result<Scene> back = readPack(path.string());
  ASSERT_TRUE(back) << back.error().message;
  expectScenesEqual(scene, *back);
  EXPECT_EQ(listing(), std::vector<std::string>{"scene.vbp"});  // no temporary file left behind
}

TEST_F(PackFileTest, RealAssetsThroughFile) {
  // The repository's assets, and DamagedHelmet (five 2048^2 textures) when the extra corpus has it.
  std::vector<fs::path> assets;
  for (const char* relative : {"CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb", "OrientationTest/glTF/OrientationTest.gltf",
                               "AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf", "CesiumMan/glTF/CesiumMan.gltf",
                               "Fox/glTF/Fox.gltf"})
    assets.push_back(assetPath(relative));
  if (auto helmet = test::extraAsset("DamagedHelmet/glTF-Binary/DamagedHelmet.glb")) assets.push_back(*helmet);
  for (const fs::path& asset : assets) {
    SCOPED_TRACE(asset.string());
    REQUIRE_ASSET(asset);
    Result<ImportedScene> imported = importGltfScene(asset.string());
    ASSERT_TRUE(imported) << imported.error().message;
    Result<Scene> scene = buildImportedScene(*imported);
    ASSERT_TRUE(scene) << scene.error().message;
    EXPECT_EQ(scene->objects.size(), imported->instances.size());
    const fs::path path = dir_ / "asset.vbp";
    ASSERT_TRUE(writePack(*scene, path.string()));
    Result<Scene> back = readPack(path.string());
    ASSERT_TRUE(back) << back.error().message;
    expectScenesEqual(*scene, *back);
  }
}

// --- damaged files
// ------------------------------------------------------------------------------------------

TEST(PackReader, TruncatedAtEverySixteenth) {
  Result<std::vector<uint8_t>> bytes = serializePack(makeTestScene());
  ASSERT_TRUE(bytes);
  for (size_t k = 0; k < 16; ++k) {
    const size_t size = bytes->size() * k / 16;
    Result<Scene> r = parsePack(bytes->data(), size, "pack.vbp");
    ASSERT_FALSE(r) << "truncated to " << size;
    EXPECT_EQ(r.error().code, ErrorCode::MalformedInput) << r.error().message;
    EXPECT_EQ(r.error().message.rfind("pack.vbp: ", 0), 0u) << r.error().message;
  }
  // Cut inside the (encoded) vertex data: the message names the section and its extent.
  const pack::SectionEntry vertices = entryOf(*bytes, sectionIndex(*bytes, "vertices"));
  const size_t cut = vertices.offset + vertices.size / 2;
  EXPECT_TRUE(failsWith(parsePack(bytes->data(), cut, "pack.vbp"),
                        "section 'vertices' runs past the end of the file (offset " +
                            std::to_string(vertices.offset) + ", size " + std::to_string(vertices.size) +
                            ", file " + std::to_string(cut) + ")"));
  // One byte short: the padding of the last section is gone, the declared file size no longer matches.
  EXPECT_TRUE(failsWith(parsePack(bytes->data(), bytes->size() - 1, "pack.vbp"), "'fileSize'"));
}

TEST(PackReader, FlippedByteInEachSectionIsAChecksumError) {
  PackWriteReport report;
  Result<std::vector<uint8_t>> bytes = serializePack(makeTestScene(), &report);
  ASSERT_TRUE(bytes);
  ASSERT_EQ(report.sections.size(), 9u + 16u);  // required + animation sections (4 morph targets, 1 rigid objects)
  PackWriteReport texturedReport;
  Result<std::vector<uint8_t>> textured = serializePack(makeTexturedTestScene(), &texturedReport);
  ASSERT_TRUE(textured);
  for (const PackSectionInfo& s : texturedReport.sections) {
    ASSERT_GT(s.size, 0u) << s.name;
    for (uint64_t at : {s.offset, s.offset + s.size / 2, s.offset + s.size - 1}) {
      std::vector<uint8_t> damaged = *textured;
      damaged[at] ^= 0x10;
      EXPECT_TRUE(failsWith(parse(damaged), "section '" + s.name + "': checksum mismatch")) << "byte " << at;
    }
  }
  for (const PackSectionInfo& s : report.sections) {
    ASSERT_GT(s.size, 0u) << s.name;
    for (uint64_t at : {s.offset, s.offset + s.size / 2, s.offset + s.size - 1}) {
      std::vector<uint8_t> damaged = *bytes;
      damaged[at] ^= 0x10;
      EXPECT_TRUE(failsWith(parse(damaged), "section '" + s.name + "': checksum mismatch")) << "byte " << at;
    }
  }
  // Header and table bytes are covered by the header checksum.
  for (size_t at : {size_t{40}, sizeof(pack::Header) + 3, sizeof(pack::Header) + 48 + 20}) {
    std::vector<uint8_t> damaged = *bytes;
    damaged[at] ^= 0x01;
    EXPECT_TRUE(failsWith(parse(damaged), "header or section table checksum mismatch")) << "byte " << at;
  }
}

TEST(PackReader, WrongMagicAndVersion) {
  Result<std::vector<uint8_t>> bytes = serializePack(makeTestScene());
  ASSERT_TRUE(bytes);
  std::vector<uint8_t> v = *bytes;
  pack::Header h = headerOf(v);
  h.version = pack::kVersion + 1;
  std::memcpy(v.data(), &h, sizeof(h));
  reseal(v);
  EXPECT_TRUE(failsWith(parse(v), "pack format version " + std::to_string(pack::kVersion + 1) + " is not supported",
                        ErrorCode::Unsupported));
  // Version 5 packs (rigid node animation as one-joint skins) and older are refused too: the user re-bakes.
  EXPECT_EQ(pack::kVersion, 6u);
  for (uint32_t old : {4u, 5u}) {
    v = *bytes;
    h = headerOf(v);
    h.version = old;
    std::memcpy(v.data(), &h, sizeof(h));
    reseal(v);
    EXPECT_TRUE(failsWith(parse(v),
                          "pack format version " + std::to_string(old) +
                              " is not supported by this build (it reads version 6); re-bake",
                          ErrorCode::Unsupported));
  }
  v = *bytes;
  v[0] = 'X';
  EXPECT_TRUE(failsWith(parse(v), "not a visbuf pack"));
  const char gltf[] = "glTF\x02\0\0\0";
  EXPECT_TRUE(failsWith(parsePack(reinterpret_cast<const uint8_t*>(gltf), 8, "pack.vbp"), "smaller than"));
}

TEST(PackReader, HugeCountsAreRejectedWithoutOverflow) {
  Result<std::vector<uint8_t>> bytes = serializePack(makeTestScene());
  ASSERT_TRUE(bytes);
  const size_t idx = sectionIndex(*bytes, "indices");
  {
    // count x elementSize overflows 64 bits (a section of 16-byte records).
    std::vector<uint8_t> v = *bytes;
    const size_t lods = sectionIndex(v, "lods");
    pack::SectionEntry e = entryOf(v, lods);
    e.count = (uint64_t{1} << 62) + 1;
    setEntry(v, lods, e);
    reseal(v);
    EXPECT_TRUE(failsWith(
        parse(v), "section 'lods': field 'count' 4611686018427387905 x 'elementSize' 16 overflows"));
  }
  {
    // A consistent but enormous count/size: range check, no allocation.
    std::vector<uint8_t> v = *bytes;
    pack::SectionEntry e = entryOf(v, idx);
    e.count = uint64_t{1} << 40;
    e.size = e.count;  // encoded bytes
    setEntry(v, idx, e);
    reseal(v);
    EXPECT_TRUE(failsWith(parse(v), "section 'indices' runs past the end of the file"));
  }
  {
    // Offset near 2^64: offset + size would wrap.
    std::vector<uint8_t> v = *bytes;
    pack::SectionEntry e = entryOf(v, idx);
    e.offset = ~uint64_t{15};
    setEntry(v, idx, e);
    reseal(v);
    EXPECT_TRUE(failsWith(parse(v), "section 'indices' runs past the end of the file"));
  }
  {
    // A mesh record whose vertex range wraps around 2^64.
    std::vector<uint8_t> v = *bytes;
    const pack::SectionEntry meshes = entryOf(v, sectionIndex(v, "meshes"));
    pack::MeshRecord m;
    std::memcpy(&m, v.data() + meshes.offset, sizeof(m));
    m.firstVertex = ~uint64_t{0} - 2;
    std::memcpy(v.data() + meshes.offset, &m, sizeof(m));
    reseal(v);
    EXPECT_TRUE(failsWith(parse(v), "section 'meshes' record 0"));
  }
  {
    std::vector<uint8_t> v = *bytes;
    pack::Header h = headerOf(v);
    h.sectionCount = 0xFFFFFFFFu;
    std::memcpy(v.data(), &h, sizeof(h));
    EXPECT_TRUE(failsWith(parse(v), "'sectionCount'"));
  }
}

TEST(PackReader, BadReferencesInsideSections) {
  Result<std::vector<uint8_t>> bytes = serializePack(makeTestScene());
  ASSERT_TRUE(bytes);
  auto editRecord = [&](const char* section, size_t record, auto edit) {
    std::vector<uint8_t> v = *bytes;
    const pack::SectionEntry e = entryOf(v, sectionIndex(v, section));
    uint8_t* at = v.data() + e.offset + record * e.elementSize;
    edit(at);
    reseal(v);
    return parse(v);
  };
  EXPECT_TRUE(failsWith(editRecord("objects", 1,
                                   [](uint8_t* p) {
                                     uint32_t m = 9;
                                     std::memcpy(p + 128, &m, 4);
                                   }),
                        "section 'objects' record 1: field 'mesh' 9"));
  EXPECT_TRUE(failsWith(editRecord("objects", 0,
                                   [](uint8_t* p) {
                                     double nan = NAN;
                                     std::memcpy(p + 8, &nan, 8);
                                   }),
                        "section 'objects' record 0: field 'transform' is not finite"));
  EXPECT_TRUE(failsWith(parse(editDecoded<uint32_t>(*bytes, "indices", 0, [](std::vector<uint32_t>& i) { i[5] = 1u << 30; })),
                        "index 5 has value 1073741824"));
  EXPECT_TRUE(failsWith(editRecord("lods", 1,
                                   [](uint8_t* p) {
                                     uint32_t n = 1u << 31;
                                     std::memcpy(p + 4, &n, 4);
                                   }),
                        "field 'indexCount' 2147483648"));
  EXPECT_TRUE(failsWith(editRecord("materials", 2,
                                   [](uint8_t* p) {
                                     uint32_t n = 1000;
                                     std::memcpy(p, &n, 4);
                                   }),
                        "section 'materials' record 2 field 'name'"));
  EXPECT_TRUE(failsWith(parse(editDecoded<gpu::Vertex>(*bytes, "vertices", 0,
                                                       [](std::vector<gpu::Vertex>& v) { v[3].px = 1e30f; })),
                        "vertex 3 lies outside field 'boundsSphere'"));
}

// `pack` with `value` written at byte `at` of record `record` of `section`, checksums resealed, then parsed.
template <typename T>
Result<Scene> parseWithField(std::vector<uint8_t> pack, const char* section, size_t record, size_t at, T value) {
  const pack::SectionEntry e = entryOf(pack, sectionIndex(pack, section));
  std::memcpy(pack.data() + e.offset + record * e.elementSize + at, &value, sizeof(value));
  reseal(pack);
  return parse(pack);
}

TEST(PackReader, BadTexturesAndStreams) {
  Result<std::vector<uint8_t>> bytes = serializePack(makeTexturedTestScene());
  ASSERT_TRUE(bytes);
  auto edit = [&](const char* section, size_t record, size_t at, auto value) {
    return parseWithField(*bytes, section, record, at, value);
  };
  EXPECT_TRUE(failsWith(edit("textures", 1, 20, uint32_t{9}), "section 'textures' record 1: 'sizeClass' 0 / 'layer' 9"));
  EXPECT_TRUE(failsWith(edit("textures", 1, 20, uint32_t{0}), "class 0 layer 0 is used twice"));
  EXPECT_TRUE(failsWith(edit("textures", 2, 12, uint32_t{1}), "section 'textures' record 2: field 'colorSpace' 1"));
  EXPECT_TRUE(failsWith(edit("textureClasses", 0, 0, uint32_t{3}), "section 'textureClasses' record 0: 'size' 3"));
  EXPECT_TRUE(failsWith(edit("textureClasses", 1, 12, uint32_t{5}), "'mipCount' 5"));
  const size_t format = offsetof(pack::TextureClassRecord, format);
  const size_t firstByte = offsetof(pack::TextureClassRecord, firstByte);
  const size_t byteCount = offsetof(pack::TextureClassRecord, byteCount);
  EXPECT_TRUE(failsWith(edit("textureClasses", 1, byteCount, uint64_t{1} << 40), "field 'byteCount' 1099511627776"));
  EXPECT_TRUE(failsWith(edit("textureClasses", 1, firstByte, ~uint64_t{15}), "is not 16-aligned inside section 'texels'"));
  EXPECT_TRUE(failsWith(edit("textureClasses", 1, firstByte, uint64_t{8}), "field 'firstByte' 8"));
  // The format: known values only, BC4 / BC5 linear only, and byteCount must be that format's size.
  EXPECT_TRUE(failsWith(edit("textureClasses", 1, format, uint32_t{5}), "field 'format' 5 is not a known texture format"));
  EXPECT_TRUE(failsWith(edit("textureClasses", 0, format, uint32_t{3}), "format bc4 must be linear"));
  EXPECT_TRUE(failsWith(edit("textureClasses", 1, format, uint32_t{1}), "mips need in format bc1"));
  EXPECT_TRUE(failsWith(edit("textureClasses", 1, format + 4, uint32_t{1}), "field 'reserved' is 1"));
  const size_t slot0 = offsetof(pack::MaterialRecord, textures);
  const size_t normalSlot = slot0 + 2 * sizeof(pack::TextureSlotRecord);
  EXPECT_TRUE(failsWith(edit("materials", 1, slot0, int32_t{99}), "record 1 texture slot 0: field 'texture' 99"));
  EXPECT_TRUE(failsWith(edit("materials", 1, slot0, int32_t{2}), "texture 2 has the wrong colour space"));
  EXPECT_TRUE(failsWith(edit("materials", 1, normalSlot + 12, uint32_t{2}), "texture slot 2: 'texCoord' 2"));
  EXPECT_TRUE(failsWith(edit("materials", 1, slot0 + 17, uint8_t{3}), "texture slot 0: 'texCoord' 1 / wrap 1 3"));
  EXPECT_TRUE(failsWith(edit("materials", 1, slot0 + 28, float{NAN}), "texture slot 0: field 'transform'"));
  EXPECT_TRUE(failsWith(edit("materials", 0, 40, float{INFINITY}), "record 0: non-finite colour, factor"));
  EXPECT_TRUE(failsWith(edit("meshStreams", 1, 0, ~uint64_t{0} - 1),
                        "tangents: encoded bytes ["));
  EXPECT_TRUE(failsWith(edit("meshStreams", 0, 8, uint64_t{1}), "section 'meshStreams' record 0"));
  EXPECT_TRUE(failsWith(parse(editDecoded<glm::vec4>(*bytes, "tangents", 1, [](std::vector<glm::vec4>& t) { t[2].w = 0.5f; })),
                        "record 1: tangent of vertex 2"));
  EXPECT_TRUE(failsWith(parse(editDecoded<glm::vec2>(*bytes, "uvs1", 1, [](std::vector<glm::vec2>& u) { u[3].x = NAN; })),
                        "record 1: non-finite uv1"));
  {
    std::vector<uint8_t> v = *bytes;  // texels renamed: textures without pixels
    pack::SectionEntry e = entryOf(v, sectionIndex(v, "texels"));
    std::strcpy(e.name, "texelz");
    setEntry(v, sectionIndex(v, "texels"), e);
    reseal(v);
    EXPECT_TRUE(failsWith(parse(v), "'textures', 'textureClasses' and 'texels' must appear together"));
  }
  {
    std::vector<uint8_t> v = *bytes;
    pack::SectionEntry e = entryOf(v, sectionIndex(v, "meshStreams"));
    std::strcpy(e.name, "meshStreamz");
    setEntry(v, sectionIndex(v, "meshStreams"), e);
    reseal(v);
    EXPECT_TRUE(failsWith(parse(v), "need section 'meshStreams'"));
  }
}

bool hasSection(const std::vector<uint8_t>& bytes, const std::string& name);

TEST(PackReader, BadReferencesInAnimationSections) {
  Result<std::vector<uint8_t>> bytes = serializePack(makeTestScene());
  ASSERT_TRUE(bytes);
  auto edit = [&](const char* section, size_t record, size_t at, auto value) {
    return parseWithField(*bytes, section, record, at, value);
  };
  EXPECT_TRUE(failsWith(edit("nodes", 2, 8, int32_t{9}), "section 'nodes' record 2: field 'parent' 9"));
  EXPECT_TRUE(failsWith(edit("nodes", 1, 8, int32_t{3}), "section 'nodes': node hierarchy has a cycle"));
  EXPECT_TRUE(failsWith(edit("nodes", 0, 16, double(NAN)), "section 'nodes' record 0: non-finite transform"));
  EXPECT_TRUE(failsWith(edit("skins", 0, 8, uint64_t{1} << 60), "section 'skins' record 0: fields 'firstJoint'"));
  EXPECT_TRUE(failsWith(edit("skins", 0, 16, uint32_t{70000}), "field 'jointCount' is 70000"));
  EXPECT_TRUE(failsWith(edit("skinJoints", 1, 0, uint32_t{40}), "joint 1 is node 40, which does not exist"));
  EXPECT_TRUE(failsWith(edit("skinJoints", 0, 8 + 3 * 8, 0.5), "inverse bind matrix 0 is not affine"));
  EXPECT_TRUE(failsWith(edit("skinnedMeshes", 0, 0, uint32_t{7}), "section 'skinnedMeshes' record 0: field 'mesh' 7"));
  EXPECT_TRUE(failsWith(edit("skinnedMeshes", 0, 8, uint64_t{1} << 40), "fields 'firstByte' 1099511627776"));
  EXPECT_TRUE(failsWith(edit("skinnedMeshes", 0, 16, uint64_t{0}), "field 'byteCount' is 0"));
  EXPECT_TRUE(failsWith(edit("skinnedMeshes", 0, 16, uint64_t{3}), "3 encoded bytes cannot hold the mesh's"));
  EXPECT_TRUE(failsWith(edit("skinnedMeshes", 0, 4, uint32_t{1}), "field 'reserved' must be 0"));
  {  // a stream cut short: the codec refuses it
    std::vector<RawSection> sections = splitPack(*bytes);
    RawSection& records = rawSection(sections, "skinnedMeshes");
    const uint64_t at = field<uint64_t>(records, 0, 8), size = field<uint64_t>(records, 0, 16);
    const std::vector<uint8_t>& data = rawSection(sections, "skinVertices").bytes;
    replaceStream(sections, "skinVertices", 0,
                  std::vector<uint8_t>(data.begin() + int64_t(at), data.begin() + int64_t(at + size - 8)));
    EXPECT_TRUE(failsWith(parse(joinPack(*bytes, sections)), "skin vertices of mesh 1 do not decode"));
  }
  EXPECT_TRUE(failsWith(parse(editDecoded<SkinVertex>(*bytes, "skinVertices", 0,
                                                      [](std::vector<SkinVertex>& v) { v[3].joints[0] = 2; })),
                        "uses joint index 2, skin 0 has 2 joints"));
  EXPECT_TRUE(failsWith(parse(editDecoded<SkinVertex>(*bytes, "skinVertices", 0,
                                                      [](std::vector<SkinVertex>& v) { v[3].weights[0] = 0.75f; })),
                        "weights sum to"));
  // (its morph record is checked first: the knot has neither skin vertices nor morph targets)
  EXPECT_TRUE(failsWith(edit("skinnedObjects", 0, 0, uint32_t{0}),
                        "section 'morphObjects' record 0: skinned object 0 draws mesh 0, which has no 'morphMeshes' record"));
  EXPECT_TRUE(failsWith(edit("skinnedObjects", 0, 4, uint32_t{1}), "field 'object' 1 / 'skin' 1 out of range"));
  // Morph targets (the box, mesh 1: 2 targets; skinned object 0 driven by node 3).
  EXPECT_TRUE(hasSection(*bytes, "morphMeshes") && hasSection(*bytes, "morphDeltas") &&
              hasSection(*bytes, "morphWeights") && hasSection(*bytes, "morphObjects"));
  EXPECT_TRUE(failsWith(edit("morphMeshes", 0, 0, uint32_t{9}), "section 'morphMeshes' record 0: field 'mesh' 9 out of range"));
  EXPECT_TRUE(failsWith(edit("morphMeshes", 0, 4, uint32_t{0}), "section 'morphMeshes' record 0: field 'targetCount' is 0"));
  EXPECT_TRUE(failsWith(edit("morphMeshes", 0, 4, uint32_t{3}), "fields 'firstDelta' 0 + 'targetCount x vertexCount'"));
  EXPECT_TRUE(failsWith(edit("morphMeshes", 0, 8, uint64_t{1} << 62), "fields 'firstDelta' 4611686018427387904"));
  EXPECT_TRUE(failsWith(edit("morphMeshes", 0, 16, uint64_t{1}), "fields 'firstWeight' 1 + 'targetCount' 2 run past the 2 records of section 'morphWeights'"));
  EXPECT_TRUE(failsWith(edit("morphDeltas", 5, 16, float(NAN)), "section 'morphMeshes' record 0: delta 5 (section 'morphDeltas' record 5) is not finite"));
  EXPECT_TRUE(failsWith(edit("morphWeights", 1, 0, INFINITY), "default weight 1 (section 'morphWeights' record 1) is not finite"));
  EXPECT_TRUE(failsWith(edit("morphObjects", 0, 0, uint32_t{1}), "section 'morphObjects' record 0: field 'skinnedObject' 1 / 'node' 3 out of range"));
  EXPECT_TRUE(failsWith(edit("morphObjects", 0, 4, uint32_t{4}), "field 'skinnedObject' 0 / 'node' 4 out of range (1 skinned objects, 4 nodes)"));
  EXPECT_TRUE(failsWith(edit("animations", 0, 24, uint32_t{1} << 31), "fields 'firstChannel' 2147483648"));
  EXPECT_TRUE(failsWith(edit("animations", 1, 8, 7.0), "duration 7 differs from the last key time 0.5"));
  EXPECT_TRUE(failsWith(edit("animSamplers", 2, 0, uint32_t{3}), "field 'interpolation' is 3"));
  EXPECT_TRUE(failsWith(edit("animSamplers", 0, 16, uint64_t{1} << 40), "fields 'firstTime' 0 + 'keyCount' 1099511627776"));
  EXPECT_TRUE(failsWith(edit("animSamplers", 1, 4, uint32_t{4}), "path 2 does not fit 4 components"));
  EXPECT_TRUE(failsWith(edit("animChannels", 0, 4, uint32_t{2}), "target node 2 has a matrix"));
  EXPECT_TRUE(failsWith(edit("animChannels", 1, 8, uint32_t{4}), "'path' 4 out of range"));
  EXPECT_TRUE(failsWith(edit("animTimes", 1, 0, 0.0f), "key times are not strictly increasing (key 1"));
  EXPECT_TRUE(failsWith(edit("animValues", 4, 0, INFINITY), "output value 4 is not finite"));
  // Rigid objects (object 2, node 1, clip 0).
  EXPECT_TRUE(hasSection(*bytes, "rigidObjects"));
  EXPECT_TRUE(failsWith(edit("rigidObjects", 0, 4, int32_t{4}),
                        "section 'rigidObjects' record 0: field 'node' 4 out of range (4 nodes)"));
  EXPECT_TRUE(failsWith(edit("rigidObjects", 0, 4, int32_t{-1}), "section 'rigidObjects' record 0: field 'node' -1"));
  EXPECT_TRUE(failsWith(edit("rigidObjects", 0, 0, uint32_t{3}),
                        "section 'rigidObjects' record 0: field 'object' 3 out of range (3 objects)"));
  EXPECT_TRUE(failsWith(edit("rigidObjects", 0, 0, uint32_t{1}), "object 1 is listed twice or is a skinned object"));
  EXPECT_TRUE(failsWith(edit("rigidObjects", 0, 8, int32_t{2}),
                        "field 'clip' 2 is not -1 or an animation index (2 animations)"));
  EXPECT_TRUE(failsWith(edit("rigidObjects", 0, 12, uint32_t{1}), "section 'rigidObjects' record 0: field 'reserved'"));
  EXPECT_TRUE(failsWith(edit("rigidObjects", 0, 16, double(NAN)), "field 'timeOffset' is not finite"));
  EXPECT_TRUE(failsWith(edit("rigidObjects", 0, 24 + 3 * 8, 0.5), "field 'placement' is not affine"));
  EXPECT_TRUE(failsWith(edit("rigidObjects", 0, 24 + 12 * 8, double(INFINITY)), "field 'placement' is not finite"));
}

// --- quantised packs
// ----------------------------------------------------------------------------------------

// makeTexturedTestScene (every optional section) with distinct vertex colours on the knot.
Scene makeQuantizeTestScene() {
  Scene scene = makeTexturedTestScene();
  for (size_t i = 0; i < scene.meshes[0].vertices.size(); ++i)
    scene.meshes[0].vertices[i].color = uint32_t(i) * 2654435761u;
  return scene;
}

pack::QuantizationRecord quantizationOf(const std::vector<uint8_t>& bytes, size_t mesh) {
  const pack::SectionEntry e = entryOf(bytes, sectionIndex(bytes, "quantization"));
  pack::QuantizationRecord r;
  std::memcpy(&r, bytes.data() + e.offset + mesh * sizeof(r), sizeof(r));
  return r;
}

bool hasSection(const std::vector<uint8_t>& bytes, const std::string& name) {
  for (size_t i = 0; i < headerOf(bytes).sectionCount; ++i)
    if (std::string(entryOf(bytes, i).name) == name) return true;
  return false;
}

// The pack with one more section appended (every existing section moves 48 bytes for the longer table), resealed.
std::vector<uint8_t> withExtraSection(const std::vector<uint8_t>& bytes, const char* name, uint32_t elementSize,
                                      const std::vector<uint8_t>& data) {
  pack::Header h = headerOf(bytes);
  const uint64_t shift = sizeof(pack::SectionEntry);  // 48, a multiple of 16
  const uint64_t tableEnd = sizeof(pack::Header) + uint64_t{h.sectionCount} * sizeof(pack::SectionEntry);
  std::vector<uint8_t> out(bytes.size() + shift + (data.size() + 15) / 16 * 16, 0);
  std::memcpy(out.data() + tableEnd + shift, bytes.data() + tableEnd, bytes.size() - tableEnd);
  for (size_t i = 0; i < h.sectionCount; ++i) {
    pack::SectionEntry e = entryOf(bytes, i);
    e.offset += shift;
    setEntry(out, i, e);
  }
  pack::SectionEntry e{};
  std::strncpy(e.name, name, pack::kSectionNameSize - 1);
  e.offset = bytes.size() + shift;
  e.size = data.size();
  e.count = data.size() / elementSize;
  e.elementSize = elementSize;
  setEntry(out, h.sectionCount, e);
  if (!data.empty()) std::memcpy(out.data() + e.offset, data.data(), data.size());
  h.sectionCount += 1;
  h.fileSize = out.size();
  std::memcpy(out.data(), &h, sizeof(h));
  reseal(out);
  return out;
}

std::vector<uint8_t> sectionBytes(const std::vector<uint8_t>& bytes, const std::string& name) {
  const pack::SectionEntry e = entryOf(bytes, sectionIndex(bytes, name));
  return {bytes.begin() + int64_t(e.offset), bytes.begin() + int64_t(e.offset + e.size)};
}

TEST(PackQuantize, RoundTripWithinHalfAStep) {
  const Scene scene = makeQuantizeTestScene();
  PackWriteReport report;
  Result<std::vector<uint8_t>> bytes = serializePack(scene, PackWriteOptions{true}, &report);
  ASSERT_TRUE(bytes) << bytes.error().message;
  ASSERT_TRUE(report.quantization.enabled);
  EXPECT_FALSE(hasSection(*bytes, "vertices"));
  uint64_t vertexCount = 0;
  for (const Mesh& m : scene.meshes) vertexCount += m.vertices.size();
  const pack::SectionEntry qv = entryOf(*bytes, sectionIndex(*bytes, "qvertices"));
  EXPECT_EQ(qv.elementSize, 1u);  // encoded bytes
  EXPECT_EQ(entryOf(*bytes, sectionIndex(*bytes, "quantization")).count, scene.meshes.size());
  EXPECT_EQ(report.quantization.vertices, vertexCount);
  EXPECT_EQ(report.quantization.bytesSaved, int64_t(12 * vertexCount) - int64_t(40 * scene.meshes.size()));

  Result<Scene> back = parse(*bytes);
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->meshes.size(), scene.meshes.size());
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    SCOPED_TRACE("mesh " + std::to_string(i));
    const Mesh& x = scene.meshes[i];
    const Mesh& y = back->meshes[i];
    const pack::QuantizationRecord q = quantizationOf(*bytes, i);
    ASSERT_EQ(x.vertices.size(), y.vertices.size());
    EXPECT_EQ(x.indices, y.indices);
    EXPECT_EQ(x.tangents, y.tangents);
    EXPECT_EQ(x.uvs1, y.uvs1);
    ASSERT_EQ(x.skinVertices.size(), y.skinVertices.size());
    EXPECT_TRUE(x.skinVertices.empty() ||  // memcmp with the null data() of empty vectors is undefined
                std::memcmp(x.skinVertices.data(), y.skinVertices.data(),
                            x.skinVertices.size() * sizeof(SkinVertex)) == 0);
    ASSERT_EQ(x.lods.size(), y.lods.size());
    for (size_t l = 0; l < x.lods.size(); ++l) {
      EXPECT_EQ(x.lods[l].firstIndex, y.lods[l].firstIndex);
      EXPECT_EQ(x.lods[l].indexCount, y.lods[l].indexCount);
      EXPECT_GE(y.lods[l].error, x.lods[l].error + report.quantization.meshMaxPositionError[i]);
    }
    EXPECT_EQ(y.boundsSphere.x, x.boundsSphere.x);  // the centre stays, the radius may grow
    EXPECT_GE(y.boundsSphere.w, x.boundsSphere.w);
    // Half a step per axis, plus float rounding of the decode (a few ulps of the largest magnitude involved).
    auto bound = [](float offset, float scale) {
      return double(scale) / 65535.0 / 2.0 + 4.0 * DBL_EPSILON + 2.0 * FLT_EPSILON * (std::abs(offset) + scale);
    };
    const double centreX = y.boundsSphere.x, centreY = y.boundsSphere.y, centreZ = y.boundsSphere.z;
    for (size_t v = 0; v < x.vertices.size(); ++v) {
      const gpu::Vertex& a = x.vertices[v];
      const gpu::Vertex& b = y.vertices[v];
      const float pa[] = {a.px, a.py, a.pz}, pb[] = {b.px, b.py, b.pz};
      for (int c = 0; c < 3; ++c) {
        if (std::abs(double(pa[c]) - double(pb[c])) > bound(q.positionOffset[c], q.positionScale[c])) {
          ADD_FAILURE() << "vertex " << v << " axis " << c << ": " << pa[c] << " -> " << pb[c];
        }
      }
      if (std::abs(double(a.u) - double(b.u)) > bound(q.uvOffset[0], q.uvScale[0]) ||
          std::abs(double(a.v) - double(b.v)) > bound(q.uvOffset[1], q.uvScale[1])) {
        ADD_FAILURE() << "vertex " << v << " uv: " << a.u << "," << a.v << " -> " << b.u << "," << b.v;
      }
      if (a.normal != b.normal || a.color != b.color) {
        ADD_FAILURE() << "vertex " << v << ": normal or colour changed";
      }
      const double d = std::sqrt((b.px - centreX) * (b.px - centreX) + (b.py - centreY) * (b.py - centreY) +
                                 (b.pz - centreZ) * (b.pz - centreZ));
      if (d > double(y.boundsSphere.w)) {
        ADD_FAILURE() << "vertex " << v << " is " << d << " from the centre, outside radius " << y.boundsSphere.w;
      }
    }
  }
  // Everything but the vertices, bounds and LOD errors is exactly the plain round trip.
  Scene rest = *back;
  rest.meshes = scene.meshes;
  expectScenesEqual(scene, rest);
  // The saving is measured on the decoded records: 12 bytes a vertex less the quantisation records.
  EXPECT_EQ(report.quantization.bytesSaved,
            int64_t(12 * vertexCount) - int64_t(entryOf(*bytes, sectionIndex(*bytes, "quantization")).size));
}

TEST(PackQuantize, ReportedErrorsMatchAnIndependentRecomputation) {
  const Scene scene = makeQuantizeTestScene();
  PackWriteReport report;
  Result<std::vector<uint8_t>> bytes = serializePack(scene, PackWriteOptions{true}, &report);
  ASSERT_TRUE(bytes);
  Result<Scene> back = parse(*bytes);
  ASSERT_TRUE(back) << back.error().message;
  // Recompute from what the reader decodes, in double: Euclidean distances per vertex.
  double maxError = 0, sumSq = 0, maxRel = 0, sumSqRel = 0, maxUv = 0, maxNormal = 0;
  size_t n = 0;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const Mesh& x = scene.meshes[i];
    const Mesh& y = back->meshes[i];
    double meshMax = 0;
    for (size_t v = 0; v < x.vertices.size(); ++v) {
      const gpu::Vertex& a = x.vertices[v];
      const gpu::Vertex& b = y.vertices[v];
      const double dx = double(a.px) - b.px, dy = double(a.py) - b.py, dz = double(a.pz) - b.pz;
      const double e = std::sqrt(dx * dx + dy * dy + dz * dz);
      const double rel = e / double(x.boundsSphere.w);
      meshMax = std::max(meshMax, e);
      maxRel = std::max(maxRel, rel);
      sumSq += e * e;
      sumSqRel += rel * rel;
      maxUv = std::max(maxUv, std::hypot(double(a.u) - b.u, double(a.v) - b.v));
      const glm::vec3 na = octDecode(a.normal), nb = octDecode(b.normal);
      maxNormal = std::max(maxNormal, double(glm::length(na - nb)));
      ++n;
    }
    maxError = std::max(maxError, meshMax);
    EXPECT_NEAR(report.quantization.meshMaxPositionError[i], meshMax, 1e-7 * meshMax + 1e-12);
    for (size_t l = 0; l < x.lods.size(); ++l) {
      EXPECT_GE(double(y.lods[l].error), double(x.lods[l].error) + meshMax) << "mesh " << i << " LOD " << l;
    }
  }
  const PackQuantizationReport& q = report.quantization;
  EXPECT_GT(maxError, 0.0);
  EXPECT_NEAR(q.maxPositionError, maxError, 1e-12 * maxError);
  EXPECT_NEAR(q.rmsPositionError, std::sqrt(sumSq / double(n)), 1e-9 * maxError);
  EXPECT_NEAR(q.maxRelativePositionError, maxRel, 1e-12 * maxRel);
  EXPECT_NEAR(q.rmsRelativePositionError, std::sqrt(sumSqRel / double(n)), 1e-9 * maxRel);
  EXPECT_NEAR(q.maxUvError, maxUv, 1e-12 * maxUv);
  EXPECT_EQ(q.maxNormalError, 0.0);
  EXPECT_EQ(maxNormal, 0.0);
  // And the magnitudes are what 16 bits give: the knot spans a few units, so errors are ~1e-5.
  EXPECT_LT(q.maxRelativePositionError, 2e-5);
}

TEST(PackReader, BadQuantizedSections) {
  Result<std::vector<uint8_t>> bytes = serializePack(makeQuantizeTestScene(), PackWriteOptions{true});
  ASSERT_TRUE(bytes);
  Result<std::vector<uint8_t>> plain = serializePack(makeQuantizeTestScene());
  ASSERT_TRUE(plain);
  auto edit = [&](const char* section, size_t record, size_t at, auto value) {
    return parseWithField(*bytes, section, record, at, value);
  };
  EXPECT_TRUE(failsWith(edit("quantization", 1, 0, float{NAN}),
                        "section 'quantization' record 1: field 'positionOffset' or 'uvOffset' is not finite"));
  EXPECT_TRUE(failsWith(edit("quantization", 0, 24, float{INFINITY}),
                        "section 'quantization' record 0: field 'positionOffset' or 'uvOffset' is not finite"));
  EXPECT_TRUE(failsWith(edit("quantization", 0, 16, -1.0f),
                        "section 'quantization' record 0: field 'positionScale' or 'uvScale' is not a finite "
                        "value >= 0"));
  EXPECT_TRUE(failsWith(edit("quantization", 1, 36, float{INFINITY}),
                        "section 'quantization' record 1: field 'positionScale' or 'uvScale' is not a finite value"));
  EXPECT_TRUE(failsWith(edit("quantization", 0, 12, 1e30f), "lies outside field 'boundsSphere'"));
  EXPECT_TRUE(failsWith(parse(editDecoded<pack::QVertexRecord>(*bytes, "qvertices", 0,
                                                                [](std::vector<pack::QVertexRecord>& q) { q[3].reserved = 7; })),
                        "section 'qvertices' (mesh 0 vertex 3): field 'reserved' is 7, expected 0"));
  EXPECT_TRUE(failsWith(edit("meshes", 1, 8, ~uint64_t{0} - 5), "section 'meshes' record 1"));
  for (const char* section : {"qvertices", "quantization"}) {
    std::vector<uint8_t> v = *bytes;
    v[entryOf(v, sectionIndex(v, section)).offset + 5] ^= 0x40;
    EXPECT_TRUE(failsWith(parse(v), "section '" + std::string(section) + "': checksum mismatch"));
  }
  {
    std::vector<uint8_t> v = *bytes;  // one record too few
    const size_t idx = sectionIndex(v, "quantization");
    pack::SectionEntry e = entryOf(v, idx);
    e.count -= 1;
    e.size -= sizeof(pack::QuantizationRecord);
    setEntry(v, idx, e);
    reseal(v);
    EXPECT_TRUE(failsWith(parse(v), "section 'quantization' has 1 records for 2 meshes"));
  }
  auto renamed = [&](const char* from, const char* to) {
    std::vector<uint8_t> v = *bytes;
    const size_t idx = sectionIndex(v, from);
    pack::SectionEntry e = entryOf(v, idx);
    std::memset(e.name, 0, sizeof(e.name));
    std::strcpy(e.name, to);
    setEntry(v, idx, e);
    reseal(v);
    return parse(v);
  };
  EXPECT_TRUE(failsWith(renamed("quantization", "quantizationX"), "section 'qvertices' needs section 'quantization'"));
  EXPECT_TRUE(failsWith(renamed("qvertices", "qverticesX"),
                        "required section 'vertices' (or 'qvertices' in a quantised pack) is missing"));
  // Both vertex sections, and a quantization section without qvertices.
  EXPECT_TRUE(failsWith(parse(withExtraSection(*bytes, "vertices", 1, sectionBytes(*plain, "vertices"))),
                        "sections 'vertices' and 'qvertices' are both present; a pack stores exactly one of them"));
  EXPECT_TRUE(failsWith(parse(withExtraSection(*plain, "quantization", 40, sectionBytes(*bytes, "quantization"))),
                        "section 'quantization' is only valid with section 'qvertices'"));
  // The helper itself produces readable packs: an unknown extra section is skipped.
  EXPECT_TRUE(parse(withExtraSection(*bytes, "extra", 1, {1, 2, 3})));
}

// --- encoded geometry (meshoptimizer codecs, "meshEncoding")
// ------------------------------------------------------------------------------------------

pack::MeshEncodingRecord encodingOf(const std::vector<uint8_t>& bytes, size_t mesh) {
  const pack::SectionEntry e = entryOf(bytes, sectionIndex(bytes, "meshEncoding"));
  pack::MeshEncodingRecord r;
  std::memcpy(&r, bytes.data() + e.offset + mesh * sizeof(r), sizeof(r));
  return r;
}

// Decodes with meshoptimizer's own API (not pack_geometry.h) and compares with the scene the pack was written from:
// every mesh's streams lie back to back in mesh order and decode to its data bit for bit.
TEST(PackGeometry, EncodedSectionsDecodeToTheSceneExactly) {
  const Scene scene = makeTexturedTestScene();
  Result<std::vector<uint8_t>> bytes = serializePack(scene);
  ASSERT_TRUE(bytes) << bytes.error().message;
  const pack::SectionEntry vertices = entryOf(*bytes, sectionIndex(*bytes, "vertices"));
  const pack::SectionEntry indices = entryOf(*bytes, sectionIndex(*bytes, "indices"));
  const pack::SectionEntry streams = entryOf(*bytes, sectionIndex(*bytes, "meshStreams"));
  const pack::SectionEntry tangents = entryOf(*bytes, sectionIndex(*bytes, "tangents"));
  const pack::SectionEntry uvs1 = entryOf(*bytes, sectionIndex(*bytes, "uvs1"));
  EXPECT_EQ(entryOf(*bytes, sectionIndex(*bytes, "meshEncoding")).count, scene.meshes.size());
  uint64_t vertexCursor = 0, indexCursor = 0, rawBytes = 0;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    SCOPED_TRACE("mesh " + std::to_string(i));
    const Mesh& m = scene.meshes[i];
    const pack::MeshEncodingRecord e = encodingOf(*bytes, i);
    EXPECT_EQ(e.vertexCount, m.vertices.size());
    EXPECT_EQ(e.indexCount, m.indices.size());
    EXPECT_EQ(e.reserved, 0u);
    EXPECT_EQ(e.vertexByte, vertexCursor);
    EXPECT_EQ(e.indexByte, indexCursor);
    vertexCursor += e.vertexBytes;
    indexCursor += e.indexBytes;
    std::vector<gpu::Vertex> v(m.vertices.size());
    ASSERT_EQ(meshopt_decodeVertexBuffer(v.data(), v.size(), sizeof(gpu::Vertex),
                                         bytes->data() + vertices.offset + e.vertexByte, e.vertexBytes), 0);
    EXPECT_EQ(std::memcmp(v.data(), m.vertices.data(), v.size() * sizeof(gpu::Vertex)), 0);
    std::vector<uint32_t> idx(m.indices.size());
    const uint8_t* at = bytes->data() + indices.offset + e.indexByte;
    ASSERT_EQ(e.indexCodec == pack::kIndexCodecTriangles
                  ? meshopt_decodeIndexBuffer(idx.data(), idx.size(), 4, at, e.indexBytes)
                  : meshopt_decodeIndexSequence(idx.data(), idx.size(), 4, at, e.indexBytes),
              0);
    EXPECT_EQ(idx, m.indices);
    pack::MeshStreamsRecord r;
    std::memcpy(&r, bytes->data() + streams.offset + i * sizeof(r), sizeof(r));
    EXPECT_EQ(r.tangentByte == pack::kNoStream, m.tangents.empty());
    if (!m.tangents.empty()) {
      std::vector<glm::vec4> t(m.vertices.size());
      ASSERT_EQ(meshopt_decodeVertexBuffer(t.data(), t.size(), 16, bytes->data() + tangents.offset + r.tangentByte,
                                           r.tangentBytes), 0);
      EXPECT_EQ(t, m.tangents);
    }
    if (!m.uvs1.empty()) {
      std::vector<glm::vec2> u(m.vertices.size());
      ASSERT_EQ(meshopt_decodeVertexBuffer(u.data(), u.size(), 8, bytes->data() + uvs1.offset + r.uv1Byte, r.uv1Bytes),
                0);
      EXPECT_EQ(u, m.uvs1);
    }
    rawBytes += m.vertices.size() * sizeof(gpu::Vertex) + m.indices.size() * sizeof(uint32_t);
  }
  EXPECT_EQ(vertexCursor, vertices.size);
  EXPECT_EQ(indexCursor, indices.size);
  EXPECT_LT(vertices.size + indices.size, rawBytes);  // it does compress
  // The same scene always gives the same bytes (pinned codec versions, no state between calls).
  Result<std::vector<uint8_t>> again = serializePack(scene);
  ASSERT_TRUE(again);
  EXPECT_TRUE(*again == *bytes);
}

// A baked asset's meshes have their triangles in the order the triangle codec reproduces (buildImportedScene), so
// every mesh uses it and the round trip is exact; an arbitrary rotation falls back to the exact sequence codec.
TEST(PackGeometry, BakedMeshesUseTheTriangleCodec) {
  for (const char* asset : {"Fox/glTF/Fox.gltf", "CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb"}) {
    SCOPED_TRACE(asset);
    Result<ImportedScene> imported = importGltfScene(assetPath(asset));
    ASSERT_TRUE(imported) << imported.error().message;
    Result<Scene> scene = buildImportedScene(*imported);
    ASSERT_TRUE(scene) << scene.error().message;
    Result<std::vector<uint8_t>> bytes = serializePack(*scene);
    ASSERT_TRUE(bytes);
    for (size_t i = 0; i < scene->meshes.size(); ++i)
      EXPECT_EQ(encodingOf(*bytes, i).indexCodec, pack::kIndexCodecTriangles) << "mesh " << i;
    Result<Scene> back = parse(*bytes);
    ASSERT_TRUE(back) << back.error().message;
    for (size_t i = 0; i < scene->meshes.size(); ++i) EXPECT_EQ(back->meshes[i].indices, scene->meshes[i].indices);
  }
  // Rotating one triangle of a codec-ordered mesh: the triangle codec would undo the rotation, so the writer keeps
  // the exact order with the sequence codec.
  Scene scene = makeTestScene(16, 6);
  std::vector<uint32_t>& idx = scene.meshes[0].indices;
  ASSERT_TRUE(pack::rotateTrianglesToCodecOrder(idx));
  Result<std::vector<uint8_t>> canonical = serializePack(scene);
  ASSERT_TRUE(canonical);
  EXPECT_EQ(encodingOf(*canonical, 0).indexCodec, pack::kIndexCodecTriangles);
  std::rotate(idx.begin() + 3, idx.begin() + 4, idx.begin() + 6);
  Result<std::vector<uint8_t>> rotated = serializePack(scene);
  ASSERT_TRUE(rotated);
  EXPECT_EQ(encodingOf(*rotated, 0).indexCodec, pack::kIndexCodecSequence);
  Result<Scene> back = parse(*rotated);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->meshes[0].indices, idx);
}

TEST(PackReader, HostileEncodedStreams) {
  const Scene scene = makeTexturedTestScene();
  Result<std::vector<uint8_t>> bytes = serializePack(scene);
  ASSERT_TRUE(bytes);
  const std::string name0 = "mesh '" + scene.meshes[0].name + "'";
  const std::string name1 = "mesh '" + scene.meshes[1].name + "'";
  auto edit = [&](const char* section, size_t record, size_t at, auto value) {
    return parseWithField(*bytes, section, record, at, value);
  };
  const pack::MeshEncodingRecord e0 = encodingOf(*bytes, 0), e1 = encodingOf(*bytes, 1);
  const uint64_t vertexSection = entryOf(*bytes, sectionIndex(*bytes, "vertices")).size;
  // A truncated stream: the codec runs out of data.
  Result<Scene> r = edit("meshEncoding", 1, 8, e1.vertexBytes - 1);
  EXPECT_TRUE(failsWith(r, "section 'meshEncoding' record 1 (" + name1 + ") vertices: the encoded stream in section "
                           "'vertices' (bytes [" + std::to_string(e1.vertexByte) + ", "));
  EXPECT_TRUE(failsWith(r, "does not decode to " + std::to_string(e1.vertexCount) + " records: "));
  r = edit("meshEncoding", 0, 24, e0.indexBytes - 1);
  EXPECT_TRUE(failsWith(r, "section 'meshEncoding' record 0 (" + name0 + ") indices: the encoded stream in section "
                           "'indices'"));
  // A damaged stream header.
  {
    std::vector<uint8_t> v = *bytes;
    v[entryOf(v, sectionIndex(v, "vertices")).offset + e1.vertexByte] = 0xFF;
    reseal(v);
    EXPECT_TRUE(failsWith(parse(v), "unsupported or damaged stream header"));
  }
  // Ranges outside the section, including one that wraps around 2^64.
  EXPECT_TRUE(failsWith(edit("meshEncoding", 1, 0, vertexSection),
                        "section 'meshEncoding' record 1 (" + name1 + ") vertices: encoded bytes [" +
                            std::to_string(vertexSection) + ", " + std::to_string(vertexSection) + " + " +
                            std::to_string(e1.vertexBytes) + ") lie outside section 'vertices' (" +
                            std::to_string(vertexSection) + " bytes)"));
  EXPECT_TRUE(failsWith(edit("meshEncoding", 0, 16, ~uint64_t{0} - 3), "lie outside section 'indices'"));
  EXPECT_TRUE(failsWith(edit("meshStreams", 1, 16, ~uint64_t{0} - 3), "uvs1: encoded bytes ["));
  // Lying sizes: the encoding record disagrees with the mesh record ...
  EXPECT_TRUE(failsWith(edit("meshEncoding", 0, 32, e0.vertexCount + 1),
                        "section 'meshEncoding' record 0 (" + name0 + "): its streams decode to " +
                            std::to_string(e0.vertexCount + 1) + " vertices / " + std::to_string(e0.indexCount) +
                            " indices, but the mesh record has " + std::to_string(e0.vertexCount) + " / " +
                            std::to_string(e0.indexCount)));
  // ... or both claim another count than the stream holds: the codec notices.
  {
    std::vector<RawSection> sections = splitPack(*bytes);
    setField<uint32_t>(rawSection(sections, "meshes"), 1, offsetof(pack::MeshRecord, vertexCount), e1.vertexCount + 16);
    setField<uint32_t>(rawSection(sections, "meshEncoding"), 1, 32, e1.vertexCount + 16);
    EXPECT_TRUE(failsWith(parse(joinPack(*bytes, sections)), "(" + name1 + ") vertices: the encoded stream"));
  }
  // A decoded size the stream cannot hold is refused before anything is allocated.
  {
    std::vector<RawSection> sections = splitPack(*bytes);
    setField<uint32_t>(rawSection(sections, "meshes"), 1, offsetof(pack::MeshRecord, vertexCount), 0xFFFFFFF0u);
    setField<uint32_t>(rawSection(sections, "meshEncoding"), 1, 32, 0xFFFFFFF0u);
    EXPECT_TRUE(failsWith(parse(joinPack(*bytes, sections)),
                          std::to_string(e1.vertexBytes) + " bytes cannot encode 4294967280 records of 32 bytes"));
  }
  EXPECT_TRUE(failsWith(edit("meshEncoding", 0, 40, uint32_t{7}), "field 'indexCodec' is 7"));
  EXPECT_TRUE(failsWith(edit("meshEncoding", 1, 44, uint32_t{1}), "field 'reserved' is 1"));
  // The triangle codec only takes whole triangles.
  {
    std::vector<RawSection> sections = splitPack(*bytes);
    setField<uint32_t>(rawSection(sections, "meshes"), 1, offsetof(pack::MeshRecord, indexCount), e1.indexCount - 1);
    setField<uint32_t>(rawSection(sections, "meshEncoding"), 1, 36, e1.indexCount - 1);
    setField<uint32_t>(rawSection(sections, "meshEncoding"), 1, 40, pack::kIndexCodecTriangles);
    EXPECT_TRUE(failsWith(parse(joinPack(*bytes, sections)), "the triangle codec needs a multiple of 3 indices"));
  }
  // Counts that do not follow the mesh order.
  EXPECT_TRUE(failsWith(edit("meshes", 1, 16, uint64_t{0}), "section 'meshes' record 1 (") );
  // The helpers themselves give readable packs.
  EXPECT_TRUE(parse(joinPack(*bytes, splitPack(*bytes))));
  EXPECT_TRUE(parse(editDecoded<uint32_t>(*bytes, "indices", 1, [](std::vector<uint32_t>&) {})));
}

TEST_F(PackFileTest, MappedReadMatchesInMemoryParseAndTruncationFailsCleanly) {
  const Scene scene = makeTexturedTestScene();
  const fs::path path = dir_ / "mapped.vbp";
  ASSERT_TRUE(writePack(scene, path.string()));
  const std::vector<uint8_t> bytes = readBytes(path);
  PackReadStats stats;
  Result<Scene> mapped = readPack(path.string(), &stats);
  ASSERT_TRUE(mapped) << mapped.error().message;
  expectScenesEqual(scene, *mapped);
  EXPECT_EQ(stats.fileBytes, bytes.size());
  uint64_t largest = 0;
  for (size_t i = 0; i < headerOf(bytes).sectionCount; ++i) largest = std::max(largest, entryOf(bytes, i).size);
  EXPECT_EQ(stats.largestSection, largest);
  EXPECT_EQ(stats.peakScratchBytes, 0u);  // plain vertices decode straight into the scene
  // Truncated on disk: the size checks against the header come before any section is touched.
  fs::resize_file(path, bytes.size() / 2);
  Result<Scene> cut = readPack(path.string());
  ASSERT_FALSE(cut);
  EXPECT_EQ(cut.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(cut.error().message.find("runs past the end of the file"), std::string::npos) << cut.error().message;
  fs::resize_file(path, 0);
  Result<Scene> empty = readPack(path.string());
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().message.find("file is 0 bytes"), std::string::npos) << empty.error().message;
  EXPECT_EQ(readPack((dir_ / "missing.vbp").string()).error().code, ErrorCode::FileNotFound);
  EXPECT_EQ(readPack(dir_.string()).error().code, ErrorCode::InvalidArgument);
  // Quantised: one mesh's 20-byte records are the only decode scratch.
  ASSERT_TRUE(writePack(scene, path.string(), PackWriteOptions{true}));
  ASSERT_TRUE(readPack(path.string(), &stats));
  size_t most = 0;
  for (const Mesh& m : scene.meshes) most = std::max(most, m.vertices.size());
  EXPECT_EQ(stats.peakScratchBytes, most * sizeof(pack::QVertexRecord));
}

// --- atomic writes
// ------------------------------------------------------------------------------------------

TEST_F(PackFileTest, FailedWriteKeepsTheOldPack) {
  const fs::path path = dir_ / "scene.vbp";
  Scene small = makeTestScene(16, 6);
  ASSERT_TRUE(writePack(small, path.string()));
  const std::vector<uint8_t> before = readBytes(path);

  // Simulate a full disk / quota: a file size limit below the new pack's size makes write() fail (EFBIG).
  Scene big = makeTestScene(256, 32);
  struct rlimit old {};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  struct sigaction ignore {
  }, previous{};
  ignore.sa_handler = SIG_IGN;
  ASSERT_EQ(sigaction(SIGXFSZ, &ignore, &previous), 0);
  struct rlimit limited = old;
  limited.rlim_cur = before.size() + 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limited), 0);
  Status s = writePack(big, path.string());
  setrlimit(RLIMIT_FSIZE, &old);
  sigaction(SIGXFSZ, &previous, nullptr);

  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::IoError);
  EXPECT_NE(s.error().message.find("write failed"), std::string::npos) << s.error().message;
  EXPECT_EQ(readBytes(path), before);                           // the old pack is intact
  EXPECT_EQ(listing(), std::vector<std::string>{"scene.vbp"});  // and no partial file is left
  EXPECT_TRUE(readPack(path.string()));
}

TEST_F(PackFileTest, DestinationProblemsLeaveNothingBehind) {
  const Scene scene = makeTestScene(16, 6);
  // The destination is a directory: the rename fails, the temporary file is removed.
  fs::create_directories(dir_ / "taken.vbp");
  Status s = writePack(scene, (dir_ / "taken.vbp").string());
  EXPECT_FALSE(s);
  EXPECT_EQ(listing(), std::vector<std::string>{"taken.vbp"});
  EXPECT_TRUE(fs::is_empty(dir_ / "taken.vbp"));
  // The folder does not exist.
  s = writePack(scene, (dir_ / "missing" / "x.vbp").string());
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("cannot create the temporary file"), std::string::npos)
      << s.error().message;
  // A scene that fails validation writes nothing.
  Scene broken = scene;
  broken.objects[0].mesh = 99;
  EXPECT_FALSE(writePack(broken, (dir_ / "broken.vbp").string()));
  EXPECT_EQ(listing(), std::vector<std::string>{"taken.vbp"});
}

TEST_F(PackFileTest, UnwritableDirectory) {
  if (geteuid() == 0)
    GTEST_SKIP() << "root ignores directory permissions (covered by FailedWriteKeepsTheOldPack)";
  const fs::path path = dir_ / "scene.vbp";
  ASSERT_TRUE(writePack(makeTestScene(16, 6), path.string()));
  const std::vector<uint8_t> before = readBytes(path);
  fs::permissions(dir_, fs::perms::owner_read | fs::perms::owner_exec);
  Status s = writePack(makeTestScene(), path.string());
  fs::permissions(dir_, fs::perms::owner_all);
  ASSERT_FALSE(s);
  EXPECT_EQ(readBytes(path), before);
  EXPECT_EQ(listing(), std::vector<std::string>{"scene.vbp"});
}

// --- fuzz
// ---------------------------------------------------------------------------------------------------

void fuzzPack(const Scene& scene, uint64_t seed, const PackWriteOptions& options = {});

// 2,000 random mutations of a valid pack (fixed seed): bit flips, random bytes, extreme integers written over
// header/table/record fields, truncation and extension. Half of them are resealed (checksums recomputed) so
// that they reach the structural and content checks. Every read must return (no crash, no sanitizer report
// under the sanitizer build); a success must be a valid scene.
TEST(PackFuzz, RandomMutationsNeverCrash) {
  for (const bool textured : {false, true}) {
    SCOPED_TRACE(textured ? "textured" : "plain");
    fuzzPack(textured ? makeTexturedTestScene() : makeTestScene(16, 6), textured ? 20240612 : 20240611);
  }
  SCOPED_TRACE("quantised");
  fuzzPack(makeTexturedTestScene(), 20261123, PackWriteOptions{true});
}

void fuzzPack(const Scene& scene, uint64_t seed, const PackWriteOptions& options) {
  Result<std::vector<uint8_t>> original = serializePack(scene, options);
  ASSERT_TRUE(original);
  Rng rng(seed);
  auto below = [&](uint64_t n) { return n == 0 ? 0 : rng.next() % n; };
  const uint64_t extremes[] = {0,
                               1,
                               3,
                               15,
                               16,
                               0x7FFFFFFF,
                               0xFFFFFFFF,
                               0x100000000ull,
                               uint64_t{1} << 62,
                               ~uint64_t{0},
                               ~uint64_t{0} - 15};
  size_t failures = 0, deep = 0, successes = 0;
  for (int iteration = 0; iteration < 2000; ++iteration) {
    std::vector<uint8_t> v = *original;
    const int mutations = 1 + static_cast<int>(below(4));
    for (int m = 0; m < mutations; ++m) {
      // Bias towards the header, the table and the small record sections at the front.
      const uint64_t span = below(4) == 0 ? v.size() : std::min<uint64_t>(v.size(), 1024);
      const uint64_t at = below(span);
      switch (below(5)) {
        case 0:
          v[at] ^= uint8_t(1u << below(8));
          break;
        case 1:
          v[at] = uint8_t(rng.next());
          break;
        case 2: {
          const uint64_t x = extremes[below(std::size(extremes))];
          const size_t width = below(2) ? 8 : 4;
          if (at + width <= v.size()) std::memcpy(v.data() + (at & ~uint64_t{3}), &x, width);
          break;
        }
        case 3:
          v.resize(below(v.size() + 1));
          break;
        case 4:
          v.resize(v.size() + 16 * (1 + below(4)), uint8_t(rng.next()));
          break;
      }
      if (v.empty()) break;
    }
    if (iteration % 2 == 0) reseal(v);
    Result<Scene> r = parsePack(v.data(), v.size(), "fuzz.vbp");
    if (r) {
      ++successes;
      EXPECT_TRUE(validateScene(*r));
    } else {
      ++failures;
      EXPECT_FALSE(r.error().message.empty());
      EXPECT_EQ(r.error().message.rfind("fuzz.vbp: ", 0), 0u) << r.error().message;
      if (r.error().message.find("checksum") == std::string::npos) ++deep;
    }
  }
  EXPECT_EQ(failures + successes, 2000u);
  EXPECT_GT(deep, 500u);  // the resealed half really exercises the structural and content checks
  std::printf("[          ] %zu rejected (%zu past the checksums), %zu accepted\n", failures, deep,
              successes);
}

}  // namespace
}  // namespace visbuf
