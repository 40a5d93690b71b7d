// Shared helpers of the pack format tests (test_pack*.cpp): generated scenes that exercise every field, the raw
// section surgery that puts bad values into packs (resealed so that they reach the content checks), and the
// quantisation and encoding records.
#pragma once

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
#include "visbuf/asset/pack_section_codec.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/generate.h"

namespace visbuf::pack_test {

namespace fs = std::filesystem;

using test::assetPath;

// A small scene that exercises every field: two meshes with LOD chains, materials of every alpha mode with
// texture references, mirrored and far-from-origin objects, a non-default camera and anchor, and skinning /
// animation data (the box mesh is skinned, object 1 a skinned object: every optional section is present).
inline Scene makeTestScene(uint32_t knotSegments = 64, uint32_t knotSides = 12) {
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
inline Scene makeTexturedTestScene() {
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
  // The material extensions: a textured clearcoat on material 1, unlit material 0.
  m.clearcoat = 0.75f;
  m.clearcoatRoughness = 0.125f;
  m.clearcoatNormalScale = -0.5f;
  m.clearcoatTexture = {-1, 2, 1, "coat.png", glm::mat3x2(1.0f), {}, 2};
  m.clearcoatRoughnessTexture.texCoord = 1;
  m.clearcoatNormalTexture.baked = 2;
  scene.materials[0].unlit = true;
  return scene;
}

inline void expectScenesEqual(const Scene& a, const Scene& b) {
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
    EXPECT_EQ(x.unlit, y.unlit);
    EXPECT_EQ(x.clearcoat, y.clearcoat);
    EXPECT_EQ(x.clearcoatRoughness, y.clearcoatRoughness);
    EXPECT_EQ(x.clearcoatNormalScale, y.clearcoatNormalScale);
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

inline std::vector<uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline pack::Header headerOf(const std::vector<uint8_t>& bytes) {
  pack::Header h;
  std::memcpy(&h, bytes.data(), sizeof(h));
  return h;
}

inline pack::SectionEntry entryOf(const std::vector<uint8_t>& bytes, size_t i) {
  pack::SectionEntry e;
  std::memcpy(&e, bytes.data() + sizeof(pack::Header) + i * sizeof(pack::SectionEntry), sizeof(e));
  return e;
}

// Writes table entry i; a raw entry's storedSize follows its size (write the table bytes directly to make them
// disagree).
inline void setEntry(std::vector<uint8_t>& bytes, size_t i, pack::SectionEntry e) {
  if (e.encoding == pack::kSectionRaw) e.storedSize = e.size;
  std::memcpy(bytes.data() + sizeof(pack::Header) + i * sizeof(pack::SectionEntry), &e, sizeof(e));
}

inline size_t sectionIndex(const std::vector<uint8_t>& bytes, const std::string& name) {
  const pack::Header h = headerOf(bytes);
  for (size_t i = 0; i < h.sectionCount; ++i)
    if (std::string(entryOf(bytes, i).name) == name) return i;
  ADD_FAILURE() << "no section " << name;
  return 0;
}

// Recomputes every section checksum that can be computed (section inside the file) and the header checksum,
// so that a deliberate edit reaches the reader's later checks instead of stopping at a checksum mismatch.
inline void reseal(std::vector<uint8_t>& bytes) {
  if (bytes.size() < sizeof(pack::Header)) return;
  pack::Header h = headerOf(bytes);
  const uint64_t count = std::min<uint64_t>(h.sectionCount, pack::kMaxSections);
  const uint64_t tableEnd = sizeof(pack::Header) + count * sizeof(pack::SectionEntry);
  if (tableEnd > bytes.size()) return;
  for (size_t i = 0; i < count; ++i) {
    pack::SectionEntry e = entryOf(bytes, i);
    if (e.offset <= bytes.size() && e.storedSize <= bytes.size() - e.offset) {
      e.crc32 = pack::crc32(bytes.data() + e.offset, e.storedSize);
      std::memcpy(bytes.data() + sizeof(pack::Header) + i * sizeof(pack::SectionEntry), &e, sizeof(e));
    }
  }
  h.headerCrc = 0;
  h.headerCrc = pack::crc32(bytes.data() + sizeof(h), tableEnd - sizeof(h), pack::crc32(&h, sizeof(h)));
  std::memcpy(bytes.data(), &h, sizeof(h));
}

inline Result<Scene> parse(const std::vector<uint8_t>& bytes) {
  return parsePack(bytes.data(), bytes.size(), "pack.vbp");
}

inline ::testing::AssertionResult failsWith(const Result<Scene>& r, const std::string& text,
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
  std::vector<uint8_t> bytes;  // as stored (splitPack: decoded, the entry raw)
};

// Sections come out decoded (zstd sections as raw ones), so edits work on decoded bytes; joinPack stores them raw.
inline std::vector<RawSection> splitPack(const std::vector<uint8_t>& bytes) {
  std::vector<RawSection> out;
  for (size_t i = 0; i < headerOf(bytes).sectionCount; ++i) {
    pack::SectionEntry e = entryOf(bytes, i);
    std::vector<uint8_t> stored(bytes.begin() + int64_t(e.offset), bytes.begin() + int64_t(e.offset + e.storedSize));
    if (e.encoding == pack::kSectionZstd) {
      Result<pack::ZstdSection> z = pack::ZstdSection::open(stored.data(), stored.size(), e.size);
      std::vector<uint8_t> decoded(e.size);
      EXPECT_TRUE(z && z->decode(0, e.size, decoded.data()));
      stored = std::move(decoded);
      e.encoding = pack::kSectionRaw;
      e.storedSize = e.size;
    }
    out.push_back({e, std::move(stored)});
  }
  return out;
}

inline std::vector<uint8_t> joinPack(const std::vector<uint8_t>& original, const std::vector<RawSection>& sections) {
  pack::Header h = headerOf(original);
  h.sectionCount = uint32_t(sections.size());
  uint64_t cursor = (sizeof(pack::Header) + sections.size() * sizeof(pack::SectionEntry) + 15) / 16 * 16;
  std::vector<pack::SectionEntry> table;
  for (const RawSection& r : sections) {
    pack::SectionEntry e = r.entry;
    e.offset = cursor;
    e.storedSize = r.bytes.size();  // RawSection::bytes are the stored bytes: decoded ones for a raw section
    if (e.encoding == pack::kSectionRaw) {
      e.size = r.bytes.size();
      e.count = e.elementSize ? e.size / e.elementSize : 0;
    }
    table.push_back(e);
    cursor += (e.storedSize + 15) / 16 * 16;
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

inline RawSection& rawSection(std::vector<RawSection>& sections, const std::string& name) {
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

inline StreamLocator locatorOf(const std::string& stream) {
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
inline void replaceStream(std::vector<RawSection>& sections, const std::string& stream, size_t mesh,
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

// makeTexturedTestScene (every optional section) with distinct vertex colours on the knot.
inline Scene makeQuantizeTestScene() {
  Scene scene = makeTexturedTestScene();
  for (size_t i = 0; i < scene.meshes[0].vertices.size(); ++i)
    scene.meshes[0].vertices[i].color = uint32_t(i) * 2654435761u;
  return scene;
}

inline pack::QuantizationRecord quantizationOf(const std::vector<uint8_t>& bytes, size_t mesh) {
  const pack::SectionEntry e = entryOf(bytes, sectionIndex(bytes, "quantization"));
  pack::QuantizationRecord r;
  std::memcpy(&r, bytes.data() + e.offset + mesh * sizeof(r), sizeof(r));
  return r;
}

inline bool hasSection(const std::vector<uint8_t>& bytes, const std::string& name) {
  for (size_t i = 0; i < headerOf(bytes).sectionCount; ++i)
    if (std::string(entryOf(bytes, i).name) == name) return true;
  return false;
}

// The pack with one more section appended (every existing section moves 64 bytes for the longer table), resealed.
inline std::vector<uint8_t> withExtraSection(const std::vector<uint8_t>& bytes, const char* name, uint32_t elementSize,
                                      const std::vector<uint8_t>& data) {
  pack::Header h = headerOf(bytes);
  const uint64_t shift = sizeof(pack::SectionEntry);  // 64, a multiple of 16
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

// A section's decoded bytes.
inline std::vector<uint8_t> sectionBytes(const std::vector<uint8_t>& bytes, const std::string& name) {
  for (RawSection& r : splitPack(bytes))
    if (std::string(r.entry.name) == name) return std::move(r.bytes);
  ADD_FAILURE() << "no section " << name;
  return {};
}

inline pack::MeshEncodingRecord encodingOf(const std::vector<uint8_t>& bytes, size_t mesh) {
  const pack::SectionEntry e = entryOf(bytes, sectionIndex(bytes, "meshEncoding"));
  pack::MeshEncodingRecord r;
  std::memcpy(&r, bytes.data() + e.offset + mesh * sizeof(r), sizeof(r));
  return r;
}

// `pack` with `value` written at byte `at` of record `record` of `section`, checksums resealed, then parsed.
template <typename T>
Result<Scene> parseWithField(std::vector<uint8_t> pack, const char* section, size_t record, size_t at, T value) {
  const pack::SectionEntry e = entryOf(pack, sectionIndex(pack, section));
  std::memcpy(pack.data() + e.offset + record * e.elementSize + at, &value, sizeof(value));
  reseal(pack);
  return parse(pack);
}

}  // namespace visbuf::pack_test
