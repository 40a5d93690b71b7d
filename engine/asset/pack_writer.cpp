// Pack writer: serialise every section into memory, lay them out 16-byte aligned, checksum, write atomically.
#include "visbuf/asset/pack_writer.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <utility>

#include "visbuf/asset/pack_animation.h"
#include "visbuf/asset/pack_format.h"
#include "visbuf/asset/pack_geometry.h"
#include "visbuf/asset/pack_section_codec.h"
#include "visbuf/core/image_io.h"
#include "visbuf/core/temp_file.h"

namespace visbuf {

namespace {

struct Section {
  const char* name;
  uint32_t elementSize;
  uint64_t count;
  std::vector<uint8_t> bytes;
};

template <typename T>
void append(std::vector<uint8_t>& out, const T& record) {
  const size_t at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &record, sizeof(T));
}

class StringTable {
 public:
  Result<pack::StringRef> add(const std::string& s) {
    if (s.size() > std::numeric_limits<uint32_t>::max() ||
        bytes_.size() + s.size() > std::numeric_limits<uint32_t>::max()) {
      return makeError(ErrorCode::CapacityExceeded, "names and URIs exceed 4 GiB in total");
    }
    pack::StringRef ref{static_cast<uint32_t>(bytes_.size()), static_cast<uint32_t>(s.size())};
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    return ref;
  }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

bool finite(glm::vec4 v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}
bool finite(glm::dvec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

uint64_t alignUp(uint64_t v) { return (v + pack::kAlignment - 1) & ~(pack::kAlignment - 1); }

std::string errnoText(int err) { return std::strerror(err); }

Error invalid(std::string message) { return makeError(ErrorCode::MalformedInput, std::move(message)); }

template <typename T>
std::vector<uint8_t> bytesOf(const std::vector<T>& v) {
  std::vector<uint8_t> out(v.size() * sizeof(T));
  if (!v.empty()) std::memcpy(out.data(), v.data(), out.size());
  return out;
}

Result<pack::TextureSlotRecord> slotRecord(const TextureRef& t, const Scene& scene, size_t slot,
                                           StringTable& strings, const std::string& where) {
  const bool enumsOk = uint32_t(t.sampler.wrapS) <= 2 && uint32_t(t.sampler.wrapT) <= 2 &&
                       uint32_t(t.sampler.magFilter) <= 1 && uint32_t(t.sampler.minFilter) <= 1 &&
                       uint32_t(t.sampler.mipFilter) <= 2;
  const float* m = &t.transform[0][0];
  if (!enumsOk || t.texCoord > 1 || !std::all_of(m, m + 6, [](float x) { return std::isfinite(x); }))
    return invalid(where + ": invalid sampler, texCoord (0 or 1) or non-finite transform");
  if (t.baked < -1 || t.baked >= int64_t(scene.textures.size()))
    return invalid(
        fmt::format("{}: baked texture {} out of range ({} textures)", where, t.baked, scene.textures.size()));
  if (t.baked >= 0 && scene.textures[size_t(t.baked)].colorSpace != textureSlotColorSpace(slot))
    return invalid(fmt::format("{}: baked texture {} has the wrong colour space for this slot", where, t.baked));
  pack::TextureSlotRecord r{};
  r.texture = t.baked;
  r.gltfTexture = t.texture;
  r.gltfImage = t.image;
  r.texCoord = t.texCoord;
  r.wrapS = uint8_t(t.sampler.wrapS);
  r.wrapT = uint8_t(t.sampler.wrapT);
  r.magFilter = uint8_t(t.sampler.magFilter);
  r.minFilter = uint8_t(t.sampler.minFilter);
  r.mipFilter = uint8_t(t.sampler.mipFilter);
  std::memcpy(r.transform, m, sizeof(r.transform));
  auto uri = strings.add(t.uri);
  if (!uri) return uri.error();
  r.uri = *uri;
  return r;
}

Result<std::vector<uint8_t>> serializeMaterials(const Scene& scene, StringTable& strings) {
  std::vector<uint8_t> out;
  for (size_t i = 0; i < scene.materials.size(); ++i) {
    const Material& m = scene.materials[i];
    const std::string where = fmt::format("material {} '{}'", i, m.name);
    const float factors[] = {m.alphaCutoff, m.emissive.x,        m.emissive.y,          m.emissive.z,
                             m.emissiveStrength, m.metallic, m.roughness,       m.normalScale,
                             m.occlusionStrength, m.clearcoat, m.clearcoatRoughness, m.clearcoatNormalScale};
    const bool factorsFinite =
        std::all_of(std::begin(factors), std::end(factors), [](float x) { return std::isfinite(x); });
    if (!finite(m.baseColor) || !factorsFinite)
      return invalid(where + ": non-finite factor or alpha cutoff");
    pack::MaterialRecord r{};
    auto name = strings.add(m.name);
    if (!name) return name.error();
    r.name = *name;
    for (int c = 0; c < 4; ++c) r.baseColor[c] = m.baseColor[c];
    for (int c = 0; c < 3; ++c) r.emissive[c] = m.emissive[c];
    r.emissiveStrength = m.emissiveStrength;
    r.metallic = m.metallic;
    r.roughness = m.roughness;
    r.normalScale = m.normalScale;
    r.occlusionStrength = m.occlusionStrength;
    r.alphaMode = static_cast<uint32_t>(m.alphaMode);
    r.alphaCutoff = m.alphaCutoff;
    r.flags = (m.doubleSided ? pack::kMaterialDoubleSided : 0u) | (m.unlit ? pack::kMaterialUnlit : 0u);
    if (!(m.clearcoat >= 0.0f && m.clearcoat <= 1.0f && m.clearcoatRoughness >= 0.0f && m.clearcoatRoughness <= 1.0f))
      return invalid(where + ": clearcoat factors outside [0,1]");
    r.clearcoat = m.clearcoat;
    r.clearcoatRoughness = m.clearcoatRoughness;
    r.clearcoatNormalScale = m.clearcoatNormalScale;
    const auto slots = textureSlots(m);
    for (size_t t = 0; t < slots.size(); ++t) {
      auto slot = slotRecord(*slots[t], scene, t, strings, where + fmt::format(" texture slot {}", t));
      if (!slot) return slot.error();
      r.textures[t] = *slot;
    }
    append(out, r);
  }
  return out;
}

Status checkTextureClasses(const Scene& scene) {
  std::vector<std::vector<uint8_t>> used(scene.textureClasses.size());
  for (size_t i = 0; i < scene.textureClasses.size(); ++i) {
    const TextureClass& c = scene.textureClasses[i];
    if (c.size < 1 || c.size > 16384 || !std::has_single_bit(c.size) || c.layers < 1 || c.layers > 256 ||
        c.mipCount != TextureClass::mipCountFor(c.size) || uint32_t(c.colorSpace) > 1 ||
        uint32_t(c.format) >= kTextureFormatCount || c.texels.size() != c.totalBytes())
      return invalid(fmt::format("texture class {}: inconsistent size, layers, mip count, format or texel bytes", i));
    // Single- and two-channel formats hold data, never colour: there is no sRGB BC4 / BC5 format.
    if ((c.format == TextureFormat::Bc4 || c.format == TextureFormat::Bc5) && c.colorSpace != ColorSpace::Linear)
      return invalid(fmt::format("texture class {}: format {} must be linear", i, textureFormatName(c.format)));
    used[i].assign(c.layers, 0);
  }
  for (size_t i = 0; i < scene.textures.size(); ++i) {
    const Texture& t = scene.textures[i];
    if (t.sizeClass >= scene.textureClasses.size() || t.layer >= scene.textureClasses[t.sizeClass].layers ||
        used[t.sizeClass][t.layer]++ || t.colorSpace != scene.textureClasses[t.sizeClass].colorSpace ||
        t.originalWidth < 1 || t.originalHeight < 1)
      return invalid(fmt::format("texture {} '{}': bad class, layer, colour space or original size", i, t.name));
  }
  return {};
}

// Appends "textures", "textureClasses" and "texels" when the scene has baked textures.
Status serializeTextures(const Scene& scene, StringTable& strings, std::vector<Section>* sections) {
  if (scene.textures.empty() && scene.textureClasses.empty()) return {};
  if (Status s = checkTextureClasses(scene); !s) return s;
  std::vector<uint8_t> textureBytes, classBytes, texels;
  for (const Texture& t : scene.textures) {
    auto name = strings.add(t.name);
    if (!name) return name.error();
    append(textureBytes, pack::TextureRecord{*name, t.sourceImage, uint32_t(t.colorSpace), t.sizeClass, t.layer,
                                             t.originalWidth, t.originalHeight});
  }
  for (const TextureClass& c : scene.textureClasses) {
    texels.resize(alignUp(texels.size()), 0);
    append(classBytes, pack::TextureClassRecord{c.size, uint32_t(c.colorSpace), c.layers, c.mipCount,
                                                uint32_t(c.format), 0, texels.size(), c.texels.size()});
    texels.insert(texels.end(), c.texels.begin(), c.texels.end());
  }
  sections->push_back(
      {pack::kTexturesSection, sizeof(pack::TextureRecord), scene.textures.size(), std::move(textureBytes)});
  sections->push_back({pack::kTextureClassesSection, sizeof(pack::TextureClassRecord), scene.textureClasses.size(),
                       std::move(classBytes)});
  const uint64_t texelCount = texels.size();
  sections->push_back({pack::kTexelsSection, 1, texelCount, std::move(texels)});
  return {};
}

// Appends `encoded` to `section` and returns where it starts.
uint64_t appendStream(std::vector<uint8_t>& section, const std::vector<uint8_t>& encoded) {
  const uint64_t at = section.size();
  section.insert(section.end(), encoded.begin(), encoded.end());
  return at;
}

// Appends "meshStreams", "tangents" and "uvs1" (encoded per mesh) when some mesh has tangents or a second uv set.
void serializeMeshStreams(const Scene& scene, std::vector<Section>* sections) {
  std::vector<pack::MeshStreamsRecord> records;
  std::vector<uint8_t> tangents, uvs1;
  bool any = false;
  for (const Mesh& m : scene.meshes) {
    pack::MeshStreamsRecord r{pack::kNoStream, 0, pack::kNoStream, 0};
    if (!m.tangents.empty()) {
      const std::vector<uint8_t> e = pack::encodeVertexStream(m.tangents.data(), m.tangents.size(), sizeof(glm::vec4));
      r.tangentByte = appendStream(tangents, e);
      r.tangentBytes = e.size();
      any = true;
    }
    if (!m.uvs1.empty()) {
      const std::vector<uint8_t> e = pack::encodeVertexStream(m.uvs1.data(), m.uvs1.size(), sizeof(glm::vec2));
      r.uv1Byte = appendStream(uvs1, e);
      r.uv1Bytes = e.size();
      any = true;
    }
    records.push_back(r);
  }
  if (!any) return;
  sections->push_back({pack::kMeshStreamsSection, sizeof(pack::MeshStreamsRecord), records.size(), bytesOf(records)});
  const uint64_t tangentBytes = tangents.size(), uv1Bytes = uvs1.size();
  if (tangentBytes > 0) sections->push_back({pack::kTangentsSection, 1, tangentBytes, std::move(tangents)});
  if (uv1Bytes > 0) sections->push_back({pack::kUvs1Section, 1, uv1Bytes, std::move(uvs1)});
}

// Picks the unorm16 q whose decoded value (pack::dequantizeUnorm16) is nearest to x in [offset, offset + scale].
uint16_t quantizeUnorm16(float offset, float scale, float x) {
  if (!(scale > 0.0f)) return 0;
  const double t = std::clamp((double(x) - double(offset)) / double(scale) * 65535.0, 0.0, 65535.0);
  const int q0 = int(std::lround(t));
  int best = q0;
  double bestError = std::numeric_limits<double>::infinity();
  for (int q = std::max(q0 - 1, 0); q <= std::min(q0 + 1, 65535); ++q) {
    const double e = std::abs(double(pack::dequantizeUnorm16(offset, scale, uint16_t(q))) - double(x));
    if (e < bestError) {
      bestError = e;
      best = q;
    }
  }
  return uint16_t(best);
}

float roundUp(double x) {
  const float f = float(x);
  return double(f) >= x ? f : std::nextafter(f, std::numeric_limits<float>::infinity());
}

struct QuantizedMesh {
  pack::QuantizationRecord params{};
  std::vector<pack::QVertexRecord> vertices;
  glm::vec4 boundsSphere{0.0f};  // the mesh's, grown to contain every decoded vertex
  float maxPositionError = 0.0f;  // rounded up; added to the LOD errors
};

// Quantises one mesh (PackWriteOptions::quantize) and accumulates its errors into `report`.
Result<QuantizedMesh> quantizeMesh(const Mesh& m, size_t index, PackQuantizationReport* report,
                                   double* sumSquares, double* sumSquaresRelative) {
  QuantizedMesh out;
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  glm::vec2 uvLo(std::numeric_limits<float>::max()), uvHi(-std::numeric_limits<float>::max());
  for (const gpu::Vertex& v : m.vertices) {
    lo = glm::min(lo, glm::vec3(v.px, v.py, v.pz));
    hi = glm::max(hi, glm::vec3(v.px, v.py, v.pz));
    uvLo = glm::min(uvLo, glm::vec2(v.u, v.v));
    uvHi = glm::max(uvHi, glm::vec2(v.u, v.v));
  }
  for (int c = 0; c < 3; ++c) {
    out.params.positionOffset[c] = lo[c];
    out.params.positionScale[c] = hi[c] - lo[c];
  }
  for (int c = 0; c < 2; ++c) {
    out.params.uvOffset[c] = uvLo[c];
    out.params.uvScale[c] = uvHi[c] - uvLo[c];
  }
  const float* all = &out.params.positionOffset[0];
  if (!std::all_of(all, all + 10, [](float x) { return std::isfinite(x); }))
    return invalid(fmt::format("mesh {} '{}': its position or uv extent overflows float; cannot quantise", index,
                               m.name));
  const glm::dvec3 centre(m.boundsSphere);
  const double radius = m.boundsSphere.w;
  double maxError = 0.0, maxDistance = 0.0;
  out.vertices.reserve(m.vertices.size());
  for (const gpu::Vertex& v : m.vertices) {
    pack::QVertexRecord q{};
    q.position[0] = quantizeUnorm16(lo.x, out.params.positionScale[0], v.px);
    q.position[1] = quantizeUnorm16(lo.y, out.params.positionScale[1], v.py);
    q.position[2] = quantizeUnorm16(lo.z, out.params.positionScale[2], v.pz);
    q.normal = v.normal;
    q.uv[0] = quantizeUnorm16(uvLo.x, out.params.uvScale[0], v.u);
    q.uv[1] = quantizeUnorm16(uvLo.y, out.params.uvScale[1], v.v);
    q.color = v.color;
    out.vertices.push_back(q);
    const gpu::Vertex d = pack::dequantizeVertex(out.params, q);
    const glm::dvec3 p(d.px, d.py, d.pz);
    const double e = glm::length(p - glm::dvec3(v.px, v.py, v.pz));
    const double rel = radius > 0.0 ? e / radius : 0.0;
    maxError = std::max(maxError, e);
    maxDistance = std::max(maxDistance, glm::length(p - centre));
    *sumSquares += e * e;
    *sumSquaresRelative += rel * rel;
    report->maxRelativePositionError = std::max(report->maxRelativePositionError, rel);
    report->maxUvError =
        std::max(report->maxUvError, glm::length(glm::dvec2(d.u, d.v) - glm::dvec2(v.u, v.v)));
    report->maxNormalError = std::max(
        report->maxNormalError, double(glm::length(octDecode(d.normal) - octDecode(v.normal))));
  }
  out.maxPositionError = roundUp(maxError);
  out.boundsSphere = glm::vec4(m.boundsSphere.x, m.boundsSphere.y, m.boundsSphere.z,
                               std::max(m.boundsSphere.w, roundUp(maxDistance)));
  report->maxPositionError = std::max(report->maxPositionError, maxError);
  report->vertices += m.vertices.size();
  report->meshMaxPositionError.push_back(out.maxPositionError);
  return out;
}

}  // namespace

Result<std::vector<uint8_t>> serializePack(const Scene& scene, PackWriteReport* report) {
  return serializePack(scene, PackWriteOptions{}, report);
}

Result<std::vector<uint8_t>> serializePack(const Scene& scene, const PackWriteOptions& options,
                                           PackWriteReport* report) {
  if (Status s = validateScene(scene); !s) return s.error();
  StringTable strings;

  // scene
  std::vector<uint8_t> sceneBytes;
  {
    const Camera& c = scene.defaultCamera;
    if (!finite(scene.anchor) || !finite(c.position) || !finite(c.target) || !finite(c.up) ||
        !std::isfinite(c.fovY) || !std::isfinite(c.nearPlane) ||
        !finite(glm::vec4(scene.lightDirection, 0.0f))) {
      return invalid("scene: non-finite anchor, camera or light direction");
    }
    pack::SceneRecord r{};
    auto name = strings.add(scene.name);
    if (!name) return name.error();
    r.name = *name;
    for (int i = 0; i < 3; ++i) {
      r.anchor[i] = scene.anchor[i];
      r.cameraPosition[i] = c.position[i];
      r.cameraTarget[i] = c.target[i];
      r.cameraUp[i] = c.up[i];
      r.lightDirection[i] = scene.lightDirection[i];
    }
    r.cameraFovY = c.fovY;
    r.cameraNear = c.nearPlane;
    append(sceneBytes, r);
  }

  // meshes, lods, vertices (or qvertices + quantization), indices; geometry encoded per mesh ("meshEncoding")
  std::vector<uint8_t> meshBytes, lodBytes, vertexBytes, indexBytes, quantizationBytes, encodingBytes;
  uint64_t vertexTotal = 0, indexTotal = 0, lodTotal = 0;
  PackQuantizationReport quantization;
  quantization.enabled = options.quantize;
  double sumSquares = 0.0, sumSquaresRelative = 0.0;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const Mesh& m = scene.meshes[i];
    if (m.vertices.size() > std::numeric_limits<uint32_t>::max() ||
        m.indices.size() > std::numeric_limits<uint32_t>::max()) {
      return makeError(ErrorCode::CapacityExceeded,
                       fmt::format("mesh {} '{}': more than 2^32-1 vertices or indices", i, m.name));
    }
    if (!finite(m.boundsSphere) || m.boundsSphere.w < 0.0f)
      return invalid(fmt::format("mesh {} '{}': invalid bounding sphere", i, m.name));
    for (size_t v = 0; v < m.vertices.size(); ++v) {
      const gpu::Vertex& vx = m.vertices[v];
      if (!std::isfinite(vx.px) || !std::isfinite(vx.py) || !std::isfinite(vx.pz) || !std::isfinite(vx.u) ||
          !std::isfinite(vx.v)) {
        return invalid(fmt::format("mesh {} '{}': vertex {} is not finite", i, m.name, v));
      }
    }
    QuantizedMesh q;
    if (options.quantize) {
      Result<QuantizedMesh> quantized = quantizeMesh(m, i, &quantization, &sumSquares, &sumSquaresRelative);
      if (!quantized) return quantized.error();
      q = std::move(quantized.value());
    }
    pack::MeshRecord r{};
    auto name = strings.add(m.name);
    if (!name) return name.error();
    r.name = *name;
    r.firstVertex = vertexTotal;
    r.firstIndex = indexTotal;
    r.vertexCount = static_cast<uint32_t>(m.vertices.size());
    r.indexCount = static_cast<uint32_t>(m.indices.size());
    r.firstLod = static_cast<uint32_t>(lodTotal);
    r.lodCount = static_cast<uint32_t>(m.lods.size());
    const glm::vec4 bounds = options.quantize ? q.boundsSphere : m.boundsSphere;
    for (int c = 0; c < 4; ++c) r.boundsSphere[c] = bounds[c];
    append(meshBytes, r);
    for (const Lod& l : m.lods) {
      if (!std::isfinite(l.error) || l.error < 0.0f)
        return invalid(
            fmt::format("mesh {} '{}': LOD error {} is not a finite value >= 0", i, m.name, l.error));
      // Quantised: the decoded mesh differs from the original by up to maxPositionError everywhere.
      const float error = options.quantize ? roundUp(double(l.error) + double(q.maxPositionError)) : l.error;
      append(lodBytes, pack::LodRecord{l.firstIndex, l.indexCount, error, 0});
    }
    pack::MeshEncodingRecord enc{};
    const std::vector<uint8_t> encodedVertices =
        options.quantize ? pack::encodeVertexStream(q.vertices.data(), q.vertices.size(), sizeof(pack::QVertexRecord))
                         : pack::encodeVertexStream(m.vertices.data(), m.vertices.size(), sizeof(gpu::Vertex));
    if (options.quantize) append(quantizationBytes, q.params);
    enc.vertexByte = appendStream(vertexBytes, encodedVertices);
    enc.vertexBytes = encodedVertices.size();
    const pack::EncodedIndices encodedIndices = pack::encodeIndexStream(m.indices.data(), m.indices.size());
    enc.indexByte = appendStream(indexBytes, encodedIndices.bytes);
    enc.indexBytes = encodedIndices.bytes.size();
    enc.vertexCount = r.vertexCount;
    enc.indexCount = r.indexCount;
    enc.indexCodec = encodedIndices.codec;
    append(encodingBytes, enc);
    vertexTotal += m.vertices.size();
    indexTotal += m.indices.size();
    lodTotal += m.lods.size();
  }

  // materials
  Result<std::vector<uint8_t>> materialBytes = serializeMaterials(scene, strings);
  if (!materialBytes) return materialBytes.error();

  // objects (validateScene checked indices and finite, non-degenerate transforms)
  std::vector<uint8_t> objectBytes;
  objectBytes.reserve(scene.objects.size() * sizeof(pack::ObjectRecord));
  for (const Object& o : scene.objects) {
    pack::ObjectRecord r{};
    for (int c = 0; c < 4; ++c)
      for (int row = 0; row < 4; ++row) r.transform[c * 4 + row] = o.transform[c][row];
    r.mesh = o.mesh;
    r.material = o.material;
    append(objectBytes, r);
  }

  // optional animation sections (pack_animation.cpp); before "strings" so their names are in it
  auto animation = pack::serializeAnimationSections(scene, [&](const std::string& s) { return strings.add(s); });
  if (!animation) return animation.error();

  std::vector<Section> sections;
  sections.push_back({pack::kSceneSection, sizeof(pack::SceneRecord), 1, std::move(sceneBytes)});
  sections.push_back(
      {pack::kMeshesSection, sizeof(pack::MeshRecord), scene.meshes.size(), std::move(meshBytes)});
  sections.push_back({pack::kLodsSection, sizeof(pack::LodRecord), lodTotal, std::move(lodBytes)});
  sections.push_back({pack::kMaterialsSection, sizeof(pack::MaterialRecord), scene.materials.size(),
                      std::move(materialBytes.value())});
  sections.push_back(
      {pack::kObjectsSection, sizeof(pack::ObjectRecord), scene.objects.size(), std::move(objectBytes)});
  sections.push_back(
      {pack::kMeshEncodingSection, sizeof(pack::MeshEncodingRecord), scene.meshes.size(), std::move(encodingBytes)});
  const uint64_t vertexStreamBytes = vertexBytes.size(), indexStreamBytes = indexBytes.size();
  if (options.quantize) {
    // Measured on the decoded records (what the GPU pool holds), independent of the encoding.
    quantization.bytesSaved = int64_t(vertexTotal * sizeof(gpu::Vertex)) -
                              int64_t(vertexTotal * sizeof(pack::QVertexRecord) + quantizationBytes.size());
    sections.push_back({pack::kQVerticesSection, 1, vertexStreamBytes, std::move(vertexBytes)});
    sections.push_back({pack::kQuantizationSection, sizeof(pack::QuantizationRecord), scene.meshes.size(),
                        std::move(quantizationBytes)});
    if (vertexTotal > 0) {
      quantization.rmsPositionError = std::sqrt(sumSquares / double(vertexTotal));
      quantization.rmsRelativePositionError = std::sqrt(sumSquaresRelative / double(vertexTotal));
    }
  } else {
    sections.push_back({pack::kVerticesSection, 1, vertexStreamBytes, std::move(vertexBytes)});
  }
  sections.push_back({pack::kIndicesSection, 1, indexStreamBytes, std::move(indexBytes)});
  serializeMeshStreams(scene, &sections);
  if (Status s = serializeTextures(scene, strings, &sections); !s) return s.error();
  for (pack::SectionData& a : *animation) sections.push_back({a.name, a.elementSize, a.count, std::move(a.bytes)});
  const uint64_t stringCount = strings.bytes().size();
  sections.push_back({pack::kStringsSection, 1, stringCount, std::move(strings.bytes())});

  // Section encodings (pack_section_codec.h), all sections in parallel; then the layout: header, table, then each
  // section's stored bytes at the next multiple of 16; the file ends 16-aligned.
  std::vector<pack::StoredSection> stored(sections.size());
  std::vector<Status> storeErrors(sections.size());
  tbb::parallel_for(size_t{0}, sections.size(), [&](size_t i) {
    Result<pack::StoredSection> r = pack::storeSection(sections[i].bytes, options.compressionLevel);
    if (r) stored[i] = std::move(r.value());
    else storeErrors[i] = r.error();
  });
  for (const Status& s : storeErrors)
    if (!s) return s.error();
  auto storedBytes = [&](size_t i) -> const std::vector<uint8_t>& {
    return stored[i].encoding == pack::kSectionRaw ? sections[i].bytes : stored[i].stored;
  };
  const uint64_t tableEnd = sizeof(pack::Header) + sections.size() * sizeof(pack::SectionEntry);
  std::vector<pack::SectionEntry> table(sections.size());
  uint64_t cursor = alignUp(tableEnd);
  for (size_t i = 0; i < sections.size(); ++i) {
    pack::SectionEntry& e = table[i];
    std::memset(&e, 0, sizeof(e));
    std::strncpy(e.name, sections[i].name, pack::kSectionNameSize - 1);
    e.offset = cursor;
    e.size = sections[i].bytes.size();
    e.count = sections[i].count;
    e.elementSize = sections[i].elementSize;
    e.storedSize = storedBytes(i).size();
    e.encoding = stored[i].encoding;
    e.crc32 = pack::crc32(storedBytes(i).data(), storedBytes(i).size());
    cursor = alignUp(cursor + e.storedSize);
  }
  pack::Header header{};
  std::memcpy(header.magic, pack::kMagic, 4);
  header.version = pack::kVersion;
  header.headerSize = sizeof(pack::Header);
  header.sectionEntrySize = sizeof(pack::SectionEntry);
  header.sectionCount = static_cast<uint32_t>(sections.size());
  header.fileSize = cursor;
  header.headerCrc = 0;
  uint32_t crc = pack::crc32(&header, sizeof(header));
  header.headerCrc = pack::crc32(table.data(), table.size() * sizeof(pack::SectionEntry), crc);

  std::vector<uint8_t> out(cursor, 0);
  std::memcpy(out.data(), &header, sizeof(header));
  std::memcpy(out.data() + sizeof(header), table.data(), table.size() * sizeof(pack::SectionEntry));
  for (size_t i = 0; i < sections.size(); ++i) {
    if (!storedBytes(i).empty()) std::memcpy(out.data() + table[i].offset, storedBytes(i).data(), table[i].storedSize);
  }
  if (report) {
    report->fileBytes = out.size();
    report->sections.clear();
    for (size_t i = 0; i < sections.size(); ++i)
      report->sections.push_back({sections[i].name, table[i].offset, table[i].size, table[i].count,
                                  table[i].storedSize, table[i].encoding});
    report->quantization = std::move(quantization);
  }
  return out;
}

Status writePack(const Scene& scene, const std::string& path, PackWriteReport* report) {
  return writePack(scene, path, PackWriteOptions{}, report);
}

Status writePack(const Scene& scene, const std::string& path, const PackWriteOptions& options,
                 PackWriteReport* report) {
  Result<std::vector<uint8_t>> bytes = serializePack(scene, options, report);
  if (!bytes) return makeError(bytes.error().code, path + ": " + bytes.error().message);

  static std::atomic<uint32_t> counter{0};
  const std::filesystem::path target(path);
  removeStaleTempFiles(target);
  const std::filesystem::path tmp =
      target.parent_path() / fmt::format(".{}.tmp{}.{}", target.filename().string(), getpid(), counter++);
  // From here until the rename, SIGINT / SIGTERM / SIGHUP remove the temporary file before ending the process.
  const TempFileGuard guard(tmp.string());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    return makeError(ErrorCode::IoError, fmt::format("{}: cannot create the temporary file '{}': {}", path,
                                                     tmp.string(), errnoText(err)));
  }
  auto fail = [&](const char* what, int err) -> Status {
    ::close(fd);
    ::unlink(tmp.c_str());
    return makeError(ErrorCode::IoError, fmt::format("{}: {} failed: {} (nothing was written to {})", path,
                                                     what, errnoText(err), path));
  };
  const uint8_t* p = bytes->data();
  size_t left = bytes->size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return fail("write", errno);
    }
    if (n == 0) return fail("write", EIO);
    p += n;
    left -= static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) return fail("fsync", errno);
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    return makeError(ErrorCode::IoError, fmt::format("{}: close failed: {}", path, errnoText(err)));
  }
  return commitFile(tmp.string(), path);
}

}  // namespace visbuf
