// Pack reader. Order of checks (docs/pack-format.md lists them for users):
//   1. header: size, magic, version, header/entry sizes, flags, section count, table inside the file;
//   2. header + table checksum;
//   3. each section: name, alignment, count x elementSize (overflow), size, encoding fields, stored range inside
//      the file, overlap, then the declared file size;
//   4. each section's checksum (over its stored bytes); the zstd sections' decoded sizes against the budget, their
//      frame tables and frame headers, their decode (texels: per class in readTextures); required sections
//      present, once, with the expected record size; exactly one of "vertices" / "qvertices", "quantization"
//      exactly with "qvertices";
//   5. contents: string refs, mesh/LOD ranges, each mesh's encoded geometry (its "meshEncoding" record: counts,
//      byte ranges, the codec's largest expansion before allocating, then the decode itself), index values,
//      finite values, object references, then the optional animation sections (pack_animation.cpp);
//   6. validateScene() on the result.
// The Parser (pack_parser.h) reads meshes and their geometry streams in pack_geometry.cpp, the rest here.
#include "visbuf/asset/pack_reader.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <new>
#include <string_view>
#include <vector>

#include "visbuf/asset/pack_animation.h"
#include "visbuf/asset/pack_format.h"
#include "visbuf/asset/pack_geometry.h"
#include "visbuf/asset/pack_parser.h"
#include "visbuf/core/file_read.h"

namespace visbuf {

namespace {

// Expected record size of the sections this reader knows.
uint32_t expectedElementSize(std::string_view name) {
  if (name == pack::kSceneSection) return sizeof(pack::SceneRecord);
  if (name == pack::kStringsSection) return 1;
  if (name == pack::kMeshesSection) return sizeof(pack::MeshRecord);
  if (name == pack::kLodsSection) return sizeof(pack::LodRecord);
  if (name == pack::kVerticesSection) return 1;  // encoded streams (pack_geometry.h)
  if (name == pack::kIndicesSection) return 1;
  if (name == pack::kMeshEncodingSection) return sizeof(pack::MeshEncodingRecord);
  if (name == pack::kMaterialsSection) return sizeof(pack::MaterialRecord);
  if (name == pack::kObjectsSection) return sizeof(pack::ObjectRecord);
  if (name == pack::kTexturesSection) return sizeof(pack::TextureRecord);
  if (name == pack::kTextureClassesSection) return sizeof(pack::TextureClassRecord);
  if (name == pack::kTexelsSection) return 1;
  if (name == pack::kMeshStreamsSection) return sizeof(pack::MeshStreamsRecord);
  if (name == pack::kTangentsSection) return 1;
  if (name == pack::kUvs1Section) return 1;
  if (name == pack::kQVerticesSection) return 1;
  if (name == pack::kQuantizationSection) return sizeof(pack::QuantizationRecord);
  return pack::animationSectionElementSize(std::string(name));  // 0: unknown
}

// Plus exactly one of "vertices" / "qvertices" (checked separately).
constexpr const char* kRequiredSections[] = {pack::kSceneSection,   pack::kStringsSection,   pack::kMeshesSection,
                                             pack::kLodsSection,    pack::kIndicesSection,   pack::kMaterialsSection,
                                             pack::kObjectsSection, pack::kMeshEncodingSection};

}  // namespace

namespace pack_detail {

Result<std::string> Parser::string(pack::StringRef ref, const std::string& where) const {
  const SectionView& s = sections_.at(pack::kStringsSection);
  if (!rangeFits(ref.offset, ref.length, s.entry.size)) {
    return fail(
        fmt::format("{}: string (offset {}, length {}) runs past the end of section 'strings' ({} bytes)",
                    where, ref.offset, ref.length, s.entry.size));
  }
  return std::string(reinterpret_cast<const char*>(s.data) + ref.offset, ref.length);
}

Status Parser::parseTable() {
  if (size_ < sizeof(pack::Header)) {
    return fail(
        fmt::format("file is {} bytes, smaller than the {}-byte pack header (truncated, or not a pack)",
                    size_, sizeof(pack::Header)));
  }
  pack::Header h;
  std::memcpy(&h, data_, sizeof(h));
  if (std::memcmp(h.magic, pack::kMagic, 4) != 0) {
    return fail(fmt::format("not a visbuf pack (magic {:02x} {:02x} {:02x} {:02x}, expected 'VBPK')",
                            uint8_t(h.magic[0]), uint8_t(h.magic[1]), uint8_t(h.magic[2]),
                            uint8_t(h.magic[3])));
  }
  if (h.version != pack::kVersion) {
    return fail(fmt::format("pack format version {} is not supported by this build (it reads version {}); "
                            "re-bake the pack with this visbuf",
                            h.version, pack::kVersion),
                ErrorCode::Unsupported);
  }
  if (h.headerSize != sizeof(pack::Header) || h.sectionEntrySize != sizeof(pack::SectionEntry)) {
    return fail(fmt::format("header fields 'headerSize' {} / 'sectionEntrySize' {} must be {} / {}",
                            h.headerSize, h.sectionEntrySize, sizeof(pack::Header),
                            sizeof(pack::SectionEntry)));
  }
  if (h.flags != 0)
    return fail(fmt::format("header field 'flags' is {:#x}; none are defined", h.flags));
  if (h.sectionCount == 0 || h.sectionCount > pack::kMaxSections) {
    return fail(fmt::format("header field 'sectionCount' is {} (1..{})", h.sectionCount, pack::kMaxSections));
  }
  const uint64_t tableEnd = sizeof(pack::Header) + uint64_t{h.sectionCount} * sizeof(pack::SectionEntry);
  if (tableEnd > size_) {
    return fail(
        fmt::format("the section table ({} entries, ends at byte {}) runs past the end of the file ({} "
                    "bytes)",
                    h.sectionCount, tableEnd, size_));
  }
  pack::Header zeroed = h;
  zeroed.headerCrc = 0;
  const uint32_t crc = pack::crc32(data_ + sizeof(pack::Header), tableEnd - sizeof(pack::Header),
                                   pack::crc32(&zeroed, sizeof(zeroed)));
  if (crc != h.headerCrc) {
    return fail(
        fmt::format("header or section table checksum mismatch (stored {:#010x}, computed {:#010x}): the "
                    "file is damaged",
                    h.headerCrc, crc));
  }

  std::vector<SectionView> views;
  for (uint32_t i = 0; i < h.sectionCount; ++i) {
    SectionView v;
    std::memcpy(&v.entry, data_ + sizeof(pack::Header) + uint64_t{i} * sizeof(pack::SectionEntry),
                sizeof(v.entry));
    const pack::SectionEntry& e = v.entry;
    const char* end = static_cast<const char*>(std::memchr(e.name, 0, pack::kSectionNameSize));
    const bool printable = end != nullptr && end != e.name &&
                           std::all_of(e.name, end, [](char c) { return c > 0x20 && c < 0x7F; });
    if (!printable)
      return fail(fmt::format("section table entry {}: the name is not NUL-terminated ASCII", i));
    v.name.assign(e.name, end);
    const std::string where = fmt::format("section '{}'", v.name);
    uint64_t bytes = 0;
    if (__builtin_mul_overflow(e.count, uint64_t{e.elementSize}, &bytes)) {
      return fail(fmt::format("{}: field 'count' {} x 'elementSize' {} overflows 64 bits", where, e.count,
                              e.elementSize));
    }
    if (bytes != e.size) {
      return fail(fmt::format("{}: field 'size' {} differs from 'count' {} x 'elementSize' {} = {}", where,
                              e.size, e.count, e.elementSize, bytes));
    }
    if (e.count > std::numeric_limits<size_t>::max() / std::max<uint64_t>(e.elementSize, 1)) {
      return fail(
          fmt::format("{}: field 'count' {} does not fit this machine's address space", where, e.count));
    }
    if (e.offset % pack::kAlignment != 0 || e.offset < tableEnd) {
      return fail(
          fmt::format("{}: field 'offset' {} must be a multiple of {} after the section table (byte {})",
                      where, e.offset, pack::kAlignment, tableEnd));
    }
    if (Status s = checkEncoding(v); !s) return s;
    if (!rangeFits(e.offset, e.storedSize, size_)) {
      return fail(fmt::format("{} runs past the end of the file (offset {}, stored size {}, file {})", where,
                              e.offset, e.storedSize, size_));
    }
    const uint32_t expected = expectedElementSize(v.name);
    if (expected != 0 && e.elementSize != expected) {
      return fail(fmt::format("{}: field 'elementSize' is {}, expected {}", where, e.elementSize, expected));
    }
    v.data = data_ + e.offset;
    if (sections_.count(v.name) != 0) return fail(fmt::format("{} appears twice", where));
    views.push_back(v);
    sections_.emplace(v.name, v);
  }
  std::sort(views.begin(), views.end(),
            [](const SectionView& a, const SectionView& b) { return a.entry.offset < b.entry.offset; });
  for (size_t i = 1; i < views.size(); ++i) {
    if (views[i].entry.offset < views[i - 1].entry.offset + views[i - 1].entry.storedSize) {
      return fail(fmt::format("section '{}' (offset {}) overlaps section '{}' (offset {}, stored size {})",
                              views[i].name, views[i].entry.offset, views[i - 1].name,
                              views[i - 1].entry.offset, views[i - 1].entry.storedSize));
    }
  }
  if (h.fileSize != size_) {
    return fail(fmt::format("header field 'fileSize' is {} but the file has {} bytes ({})", h.fileSize, size_,
                            h.fileSize > size_ ? "truncated" : "trailing bytes"));
  }
  for (const SectionView& v : views) {
    const uint32_t c = pack::crc32(v.data, v.entry.storedSize);
    if (c != v.entry.crc32) {
      return fail(
          fmt::format("section '{}': checksum mismatch (stored {:#010x}, computed {:#010x}): the file is "
                      "damaged",
                      v.name, v.entry.crc32, c));
    }
  }
  if (Status s = decodeSections(); !s) return s;
  for (const char* name : kRequiredSections) {
    if (sections_.count(name) == 0) return fail(fmt::format("required section '{}' is missing", name));
  }
  const bool plain = sections_.count(pack::kVerticesSection) != 0;
  const bool quantized = sections_.count(pack::kQVerticesSection) != 0;
  if (plain && quantized)
    return fail("sections 'vertices' and 'qvertices' are both present; a pack stores exactly one of them");
  if (!plain && !quantized)
    return fail("required section 'vertices' (or 'qvertices' in a quantised pack) is missing");
  if (quantized != (sections_.count(pack::kQuantizationSection) != 0)) {
    return fail(quantized ? "section 'qvertices' needs section 'quantization'"
                          : "section 'quantization' is only valid with section 'qvertices'");
  }
  return {};
}

Status Parser::checkEncoding(const SectionView& v) const {
  const pack::SectionEntry& e = v.entry;
  if (e.reserved != 0)
    return fail(fmt::format("section '{}': field 'reserved' is {}, expected 0", v.name, e.reserved));
  if (e.encoding == pack::kSectionRaw) {
    if (e.storedSize != e.size)
      return fail(fmt::format("section '{}': field 'storedSize' {} differs from 'size' {} (raw encoding)", v.name,
                              e.storedSize, e.size));
    return {};
  }
  if (e.encoding != pack::kSectionZstd)
    return fail(fmt::format("section '{}': field 'encoding' {} is unknown (0 raw, 1 zstd)", v.name, e.encoding));
  if (e.size == 0 || e.storedSize == 0)
    return fail(fmt::format("section '{}': a zstd section of size {} / stored size {}: empty sections are raw",
                            v.name, e.size, e.storedSize));
  return {};
}

// After the checksums: the zstd sections' declared sizes against the budget (before anything is allocated), then
// each one's frame table and frame headers (ZstdSection::open), then the decode of every zstd section but
// "texels" (readTextures decodes those per class, straight into the class).
Status Parser::decodeSections() {
  uint64_t total = 0;
  for (const auto& [name, v] : sections_) {
    if (v.entry.encoding != pack::kSectionZstd) continue;
    if (__builtin_add_overflow(total, v.entry.size, &total) || total > options_.maxDecodedBytes)
      return fail(fmt::format("the zstd sections decode to more than the reader's budget of {} bytes (section '{}' "
                              "declares {}); raise it with --max-import-memory (PackReadOptions::maxDecodedBytes)",
                              options_.maxDecodedBytes, name, v.entry.size),
                  ErrorCode::CapacityExceeded);
  }
  for (auto& [name, v] : sections_) {
    if (v.entry.encoding != pack::kSectionZstd) continue;
    Result<pack::ZstdSection> z = pack::ZstdSection::open(v.data, v.entry.storedSize, v.entry.size);
    if (!z) return fail(fmt::format("section '{}': {}", name, z.error().message));
    v.zstd = std::make_shared<const pack::ZstdSection>(std::move(z.value()));
    if (name == pack::kTexelsSection) continue;
    std::vector<uint8_t>& out = decoded_.emplace_back(v.entry.size);
    if (Status s = v.zstd->decode(0, v.entry.size, out.data()); !s)
      return fail(fmt::format("section '{}': {}", name, s.error().message));
    v.data = out.data();
  }
  return {};
}

Status Parser::readScene(Scene* scene) {
  const SectionView& s = sections_.at(pack::kSceneSection);
  if (s.entry.count != 1) return fail(fmt::format("section 'scene': {} records, expected 1", s.entry.count));
  const auto r = record<pack::SceneRecord>(s, 0);
  auto name = string(r.name, "section 'scene' field 'name'");
  if (!name) return name.error();
  scene->name = *name;
  if (!allFinite(r.anchor, 3) || !allFinite(r.cameraPosition, 3) || !allFinite(r.cameraTarget, 3) ||
      !allFinite(r.cameraUp, 3) || !allFinite(r.lightDirection, 3)) {
    return fail("section 'scene': non-finite anchor, camera or light direction");
  }
  if (!(r.cameraFovY > 0.0 && r.cameraFovY < 3.14159)) {
    return fail(fmt::format("section 'scene' field 'cameraFovY' {} is not in (0, pi)", r.cameraFovY));
  }
  if (!(r.cameraNear > 0.0) || !std::isfinite(r.cameraNear)) {
    return fail(
        fmt::format("section 'scene' field 'cameraNear' {} must be a positive distance", r.cameraNear));
  }
  const glm::vec3 light(r.lightDirection[0], r.lightDirection[1], r.lightDirection[2]);
  if (!(glm::length(light) > 0.0f)) return fail("section 'scene' field 'lightDirection' is zero");
  scene->anchor = {r.anchor[0], r.anchor[1], r.anchor[2]};
  scene->defaultCamera.position = {r.cameraPosition[0], r.cameraPosition[1], r.cameraPosition[2]};
  scene->defaultCamera.target = {r.cameraTarget[0], r.cameraTarget[1], r.cameraTarget[2]};
  scene->defaultCamera.up = {r.cameraUp[0], r.cameraUp[1], r.cameraUp[2]};
  scene->defaultCamera.fovY = r.cameraFovY;
  scene->defaultCamera.nearPlane = r.cameraNear;
  scene->lightDirection = light;
  return {};
}

Result<TextureRef> Parser::readTextureSlot(const pack::TextureSlotRecord& r, size_t slot, const Scene& scene,
                                           const std::string& where) const {
  auto uri = string(r.uri, where + " field 'uri'");
  if (!uri) return uri.error();
  if (r.texture < -1 || r.texture >= int64_t(scene.textures.size()))
    return fail(fmt::format("{}: field 'texture' {} is not -1 or below the {} textures", where, r.texture,
                            scene.textures.size()));
  if (r.texture >= 0 && scene.textures[size_t(r.texture)].colorSpace != textureSlotColorSpace(slot))
    return fail(fmt::format("{}: texture {} has the wrong colour space for this slot", where, r.texture));
  if (r.gltfTexture < -1 || r.gltfImage < -1)
    return fail(where + ": fields 'gltfTexture' / 'gltfImage' must be >= -1");
  if (r.texCoord > 1 || r.wrapS > 2 || r.wrapT > 2 || r.magFilter > 1 || r.minFilter > 1 || r.mipFilter > 2)
    return fail(fmt::format("{}: 'texCoord' {} / wrap {} {} / filters {} {} {} out of range", where, r.texCoord,
                            r.wrapS, r.wrapT, r.magFilter, r.minFilter, r.mipFilter));
  if (!allFinite(r.transform, 6)) return fail(where + ": field 'transform' is not finite");
  TextureRef t;
  t.baked = r.texture;
  t.texture = r.gltfTexture;
  t.image = r.gltfImage;
  t.texCoord = r.texCoord;
  t.uri = *uri;
  t.sampler = {WrapMode(r.wrapS), WrapMode(r.wrapT), TextureFilter(r.magFilter), TextureFilter(r.minFilter),
               MipFilter(r.mipFilter)};
  std::memcpy(&t.transform[0][0], r.transform, sizeof(r.transform));
  return t;
}

Status Parser::readMaterials(Scene* scene) {
  const SectionView& s = sections_.at(pack::kMaterialsSection);
  if (s.entry.count == 0) return fail("section 'materials' is empty: a pack needs at least one material");
  scene->materials.reserve(s.entry.count);
  for (uint64_t i = 0; i < s.entry.count; ++i) {
    const auto r = record<pack::MaterialRecord>(s, i);
    const std::string where = fmt::format("section 'materials' record {}", i);
    auto name = string(r.name, where + " field 'name'");
    if (!name) return name.error();
    const float factors[] = {r.alphaCutoff, r.emissiveStrength, r.metallic, r.roughness, r.normalScale,
                             r.occlusionStrength, r.clearcoatNormalScale};
    if (!allFinite(r.baseColor, 4) || !allFinite(r.emissive, 3) || !allFinite(factors, 7))
      return fail(where + ": non-finite colour, factor or 'alphaCutoff'");
    if (!(r.clearcoat >= 0.0f && r.clearcoat <= 1.0f) || !(r.clearcoatRoughness >= 0.0f && r.clearcoatRoughness <= 1.0f))
      return fail(fmt::format("{}: field 'clearcoat' {} / 'clearcoatRoughness' {} outside [0, 1]", where, r.clearcoat,
                              r.clearcoatRoughness));
    if (r.reserved != 0 || r.reserved2 != 0)
      return fail(fmt::format("{}: field 'reserved' / 'reserved2' is {} / {}, expected 0", where, r.reserved, r.reserved2));
    if (r.alphaMode > uint32_t(AlphaMode::Blend))
      return fail(fmt::format("{}: field 'alphaMode' is {} (0 opaque, 1 mask, 2 blend)", where, r.alphaMode));
    if ((r.flags & ~(pack::kMaterialDoubleSided | pack::kMaterialUnlit)) != 0)
      return fail(fmt::format("{}: field 'flags' {:#x} has unknown bits", where, r.flags));
    Material m;
    m.name = *name;
    m.baseColor = glm::vec4(r.baseColor[0], r.baseColor[1], r.baseColor[2], r.baseColor[3]);
    m.emissive = glm::vec3(r.emissive[0], r.emissive[1], r.emissive[2]);
    m.emissiveStrength = r.emissiveStrength;
    m.metallic = r.metallic;
    m.roughness = r.roughness;
    m.normalScale = r.normalScale;
    m.occlusionStrength = r.occlusionStrength;
    m.alphaMode = AlphaMode(r.alphaMode);
    m.alphaCutoff = r.alphaCutoff;
    m.doubleSided = (r.flags & pack::kMaterialDoubleSided) != 0;
    m.unlit = (r.flags & pack::kMaterialUnlit) != 0;
    m.clearcoat = r.clearcoat;
    m.clearcoatRoughness = r.clearcoatRoughness;
    m.clearcoatNormalScale = r.clearcoatNormalScale;
    const auto slots = textureSlots(m);
    for (size_t t = 0; t < slots.size(); ++t) {
      auto ref = readTextureSlot(r.textures[t], t, *scene, fmt::format("{} texture slot {}", where, t));
      if (!ref) return ref.error();
      *slots[t] = std::move(ref.value());
    }
    scene->materials.push_back(std::move(m));
  }
  return {};
}

Status Parser::readTextures(Scene* scene) {
  const SectionView textures = optional(pack::kTexturesSection);
  const SectionView classes = optional(pack::kTextureClassesSection);
  const SectionView texels = optional(pack::kTexelsSection);
  const int present = (textures.data != nullptr) + (classes.data != nullptr) + (texels.data != nullptr);
  if (present == 0) return {};
  if (present != 3) return fail("sections 'textures', 'textureClasses' and 'texels' must appear together");
  std::vector<uint64_t> ranges;  // each class's firstByte in "texels"
  for (uint64_t i = 0; i < classes.entry.count; ++i) {
    const auto r = record<pack::TextureClassRecord>(classes, i);
    const std::string where = fmt::format("section 'textureClasses' record {}", i);
    TextureClass c;
    c.size = r.size;
    c.colorSpace = ColorSpace(r.colorSpace);
    c.layers = r.layers;
    c.mipCount = r.mipCount;
    c.format = TextureFormat(r.format);
    if (r.size < 1 || r.size > 16384 || !std::has_single_bit(r.size) || r.colorSpace > 1 || r.layers < 1 ||
        r.layers > 256 || r.mipCount != TextureClass::mipCountFor(r.size)) {
      return fail(fmt::format("{}: 'size' {} (power of two, 1..16384) / 'colorSpace' {} / 'layers' {} (1..256) / "
                              "'mipCount' {} (log2(size) + 1) invalid",
                              where, r.size, r.colorSpace, r.layers, r.mipCount));
    }
    if (r.format >= kTextureFormatCount)
      return fail(fmt::format("{}: field 'format' {} is not a known texture format (0 rgba8, 1 bc1, 2 bc3, 3 bc4, "
                              "4 bc5)", where, r.format));
    if ((c.format == TextureFormat::Bc4 || c.format == TextureFormat::Bc5) && c.colorSpace != ColorSpace::Linear)
      return fail(fmt::format("{}: format {} must be linear (field 'colorSpace' is {})", where,
                              textureFormatName(c.format), r.colorSpace));
    if (r.reserved != 0) return fail(fmt::format("{}: field 'reserved' is {}, expected 0", where, r.reserved));
    if (r.byteCount != c.totalBytes())
      return fail(fmt::format("{}: field 'byteCount' {} differs from the {} bytes its mips need in format {}", where,
                              r.byteCount, c.totalBytes(), textureFormatName(c.format)));
    if (r.firstByte % pack::kAlignment != 0 || !rangeFits(r.firstByte, r.byteCount, texels.entry.size))
      return fail(fmt::format("{}: field 'firstByte' {} (+ {} bytes) is not 16-aligned inside section 'texels' ({} "
                              "bytes)", where, r.firstByte, r.byteCount, texels.entry.size));
    scene->textureClasses.push_back(std::move(c));
    ranges.push_back(r.firstByte);
  }
  if (Status s = readTexels(texels, ranges, scene); !s) return s;
  std::vector<std::vector<uint8_t>> used;
  for (const TextureClass& c : scene->textureClasses) used.emplace_back(c.layers, 0);
  for (uint64_t i = 0; i < textures.entry.count; ++i) {
    const auto r = record<pack::TextureRecord>(textures, i);
    const std::string where = fmt::format("section 'textures' record {}", i);
    auto name = string(r.name, where + " field 'name'");
    if (!name) return name.error();
    if (r.sizeClass >= scene->textureClasses.size() || r.layer >= scene->textureClasses[r.sizeClass].layers)
      return fail(fmt::format("{}: 'sizeClass' {} / 'layer' {} out of range", where, r.sizeClass, r.layer));
    if (used[r.sizeClass][r.layer]++)
      return fail(fmt::format("{}: class {} layer {} is used twice", where, r.sizeClass, r.layer));
    if (r.colorSpace != uint32_t(scene->textureClasses[r.sizeClass].colorSpace))
      return fail(fmt::format("{}: field 'colorSpace' {} differs from its class's", where, r.colorSpace));
    if (r.sourceImage < -1 || r.originalWidth < 1 || r.originalHeight < 1)
      return fail(where + ": 'sourceImage' < -1 or an original size of 0");
    scene->textures.push_back({*name, r.sourceImage, ColorSpace(r.colorSpace), r.sizeClass, r.layer,
                               r.originalWidth, r.originalHeight});
  }
  return {};
}

// Each class's texels from its checked range of "texels": copied from a raw section; from a zstd one, the frames
// of all classes decoded in parallel straight into the classes (no decoded copy of the whole section).
Status Parser::readTexels(const SectionView& texels, const std::vector<uint64_t>& firstBytes, Scene* scene) {
  std::vector<TextureClass>& classes = scene->textureClasses;
  if (!texels.zstd) {
    for (size_t i = 0; i < classes.size(); ++i)
      classes[i].texels.assign(texels.data + firstBytes[i], texels.data + firstBytes[i] + classes[i].totalBytes());
    return {};
  }
  uint64_t scratch = 0;
  for (size_t i = 0; i < classes.size(); ++i) {
    classes[i].texels.resize(classes[i].totalBytes());
    scratch += texels.zstd->scratchBytes(firstBytes[i], firstBytes[i] + classes[i].totalBytes());
  }
  noteScratch(scratch);
  std::vector<Status> results(classes.size());
  tbb::parallel_for(size_t{0}, classes.size(), [&](size_t i) {
    results[i] = texels.zstd->decode(firstBytes[i], firstBytes[i] + classes[i].totalBytes(), classes[i].texels.data());
  });
  for (size_t i = 0; i < classes.size(); ++i)
    if (!results[i]) return fail(fmt::format("section 'texels' (class {}): {}", i, results[i].error().message));
  return {};
}

Status Parser::readObjects(Scene* scene) {
  const SectionView& s = sections_.at(pack::kObjectsSection);
  scene->objects.reserve(s.entry.count);
  for (uint64_t i = 0; i < s.entry.count; ++i) {
    const auto r = record<pack::ObjectRecord>(s, i);
    const std::string where = fmt::format("section 'objects' record {}", i);
    if (r.mesh >= scene->meshes.size() || r.material >= scene->materials.size()) {
      return fail(fmt::format("{}: field 'mesh' {} / 'material' {} out of range ({} meshes, {} materials)",
                              where, r.mesh, r.material, scene->meshes.size(), scene->materials.size()));
    }
    if (!allFinite(r.transform, 16)) return fail(where + ": field 'transform' is not finite");
    if (r.transform[3] != 0.0 || r.transform[7] != 0.0 || r.transform[11] != 0.0 || r.transform[15] != 1.0)
      return fail(where + ": field 'transform' is not affine (last row must be 0 0 0 1)");
    Object o;
    for (int c = 0; c < 4; ++c)
      for (int row = 0; row < 4; ++row) o.transform[c][row] = r.transform[c * 4 + row];
    if (!(std::abs(glm::determinant(glm::dmat3(o.transform))) >= 1e-30))
      return fail(where + ": field 'transform' is degenerate (zero scale)");
    o.mesh = r.mesh;
    o.material = r.material;
    scene->objects.push_back(o);
  }
  return {};
}

Result<Scene> Parser::run() {
  if (Status s = parseTable(); !s) return s.error();
  Scene scene;
  if (Status s = readScene(&scene); !s) return s.error();
  if (Status s = readMeshes(&scene); !s) return s.error();
  if (Status s = readMeshStreams(&scene); !s) return s.error();
  if (Status s = readTextures(&scene); !s) return s.error();
  if (Status s = readMaterials(&scene); !s) return s.error();
  if (Status s = readObjects(&scene); !s) return s.error();
  auto find = [&](const char* name) {
    auto it = sections_.find(name);
    return it == sections_.end() ? pack::SectionBytes{} : pack::SectionBytes{it->second.data, it->second.entry.count};
  };
  auto readString = [&](pack::StringRef ref, const std::string& where) { return string(ref, where); };
  if (Status s = pack::readAnimationSections(find, readString, label_, &scene); !s) return s.error();
  if (Status s = validateScene(scene); !s) return fail(s.error().message);
  return scene;
}

}  // namespace pack_detail

using pack_detail::Parser;

Result<Scene> parsePack(const uint8_t* data, size_t size, const std::string& label, PackReadStats* stats) {
  return parsePack(data, size, label, PackReadOptions{}, stats);
}

Result<Scene> parsePack(const uint8_t* data, size_t size, const std::string& label, const PackReadOptions& options,
                        PackReadStats* stats) {
  try {
    Parser parser(data, size, label, options);
    Result<Scene> scene = parser.run();
    if (stats) {
      stats->fileBytes = size;
      stats->largestSection = parser.largestSection();
      stats->peakScratchBytes = parser.peakScratchBytes();
    }
    return scene;
  } catch (const std::bad_alloc&) {
    return makeError(ErrorCode::CapacityExceeded, label + ": out of memory while reading the pack");
  }
}

// Only a regular file is read, opened without blocking (core/file_read.h): a FIFO or device given as a pack fails
// at once instead of hanging in open(). The whole file is read once into private memory (readFileSnapshot), and
// every check (the checksums first) and every decode works on that copy: another program that truncates or
// overwrites the file in place meanwhile can neither raise SIGBUS nor change a byte after its checksum was
// verified. A change during the read itself is caught by readFileSnapshot (size / mtime / ctime differ before and
// after) or by the checksums.
Result<Scene> readPack(const std::string& path, PackReadStats* stats) { return readPack(path, PackReadOptions{}, stats); }

Result<Scene> readPack(const std::string& path, const PackReadOptions& options, PackReadStats* stats) {
  FileReadOptions fileOptions;
  fileOptions.maxBytes = kMaxPackFileBytes;
  Result<FileSnapshot> file = readFileSnapshot(path, fileOptions);
  if (!file) return file.error();
  return parsePack(file->data(), file->size, path, options, stats);
}

bool isPackFile(const std::string& path) {
  Result<std::vector<uint8_t>> magic = readFilePrefix(path, 4);
  return magic && magic->size() == 4 && std::memcmp(magic->data(), pack::kMagic, 4) == 0;
}

}  // namespace visbuf
