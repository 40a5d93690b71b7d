// The pack reader against hostile packs: truncation, checksums, versions, overflowing counts, bad references in
// every section, bad textures and streams, bad quantised sections and hostile encoded streams. Each gets a clear
// error, never a crash or a half-read scene.
#include "pack_test_util.h"

#include <fcntl.h>
#include <unistd.h>

#include "visbuf/core/mapped_file.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <thread>

namespace visbuf {
namespace {

using namespace pack_test;

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
                            std::to_string(vertices.offset) + ", stored size " + std::to_string(vertices.storedSize) +
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
    for (uint64_t at : {s.offset, s.offset + s.storedSize / 2, s.offset + s.storedSize - 1}) {
      std::vector<uint8_t> damaged = *textured;
      damaged[at] ^= 0x10;
      EXPECT_TRUE(failsWith(parse(damaged), "section '" + s.name + "': checksum mismatch")) << "byte " << at;
    }
  }
  for (const PackSectionInfo& s : report.sections) {
    ASSERT_GT(s.size, 0u) << s.name;
    for (uint64_t at : {s.offset, s.offset + s.storedSize / 2, s.offset + s.storedSize - 1}) {
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
  // Version 6 packs (48-byte section entries, no encodings; the material record without the extensions' fields)
  // and older are refused too: the user re-bakes.
  EXPECT_EQ(pack::kVersion, 7u);
  for (uint32_t old : {4u, 5u, 6u}) {
    v = *bytes;
    h = headerOf(v);
    h.version = old;
    std::memcpy(v.data(), &h, sizeof(h));
    reseal(v);
    EXPECT_TRUE(failsWith(parse(v),
                          "pack format version " + std::to_string(old) +
                              " is not supported by this build (it reads version 7); re-bake",
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
    e.encoding = pack::kSectionRaw;  // (a zstd section would stop at the decode budget first: test_pack_zstd.cpp)
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
  // The extensions' fields: unknown flag bits, a coat weight outside [0,1], a non-finite coat normal scale, the
  // reserved words, and a coat texture in the wrong colour space.
  EXPECT_TRUE(failsWith(edit("materials", 0, offsetof(pack::MaterialRecord, flags), uint32_t{4}), "field 'flags' 0x4"));
  EXPECT_TRUE(failsWith(edit("materials", 1, offsetof(pack::MaterialRecord, clearcoat), float{-0.5f}),
                        "field 'clearcoat' -0.5 / 'clearcoatRoughness' 0.125 outside [0, 1]"));
  EXPECT_TRUE(failsWith(edit("materials", 1, offsetof(pack::MaterialRecord, clearcoatRoughness), float{1.5f}),
                        "'clearcoatRoughness' 1.5 outside"));
  EXPECT_TRUE(failsWith(edit("materials", 1, offsetof(pack::MaterialRecord, clearcoatNormalScale), float{NAN}),
                        "record 1: non-finite colour, factor"));
  EXPECT_TRUE(failsWith(edit("materials", 1, offsetof(pack::MaterialRecord, reserved2), uint32_t{1}),
                        "field 'reserved' / 'reserved2' is 0 / 1"));
  EXPECT_TRUE(failsWith(edit("materials", 1, slot0 + 7 * sizeof(pack::TextureSlotRecord), int32_t{0}),
                        "texture slot 7: texture 0 has the wrong colour space"));
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

}  // namespace
}  // namespace visbuf
