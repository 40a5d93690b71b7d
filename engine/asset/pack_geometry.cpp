#include "visbuf/asset/pack_geometry.h"

#include <fmt/format.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <mutex>
#include <vector>

#include "visbuf/asset/pack_format.h"
#include "visbuf/asset/pack_parser.h"

namespace visbuf::pack {

namespace {

// meshoptimizer keeps the encoder versions in globals: set them once, before the first encode, so that encoders
// running on several threads (parallel bakes) never race on them.
void pinEncoderVersions() {
  static std::once_flag once;
  std::call_once(once, [] {
    meshopt_encodeVertexVersion(0);
    meshopt_encodeIndexVersion(1);
  });
}

std::string codecError(int rc) {
  switch (rc) {
    case -1: return "unsupported or damaged stream header (codec error -1)";
    case -2: return "the stream ends before its data does (truncated or too short; codec error -2)";
    case -3: return "the stream's size does not match the decoded count (codec error -3)";
    default: return "codec error " + std::to_string(rc);
  }
}

std::vector<uint32_t> decodeTriangles(const std::vector<uint8_t>& bytes, size_t count) {
  std::vector<uint32_t> out(count);
  if (meshopt_decodeIndexBuffer(out.data(), count, sizeof(uint32_t), bytes.data(), bytes.size()) != 0) out.clear();
  return out;
}

std::vector<uint8_t> encodeTriangles(const uint32_t* indices, size_t count) {
  pinEncoderVersions();
  const uint32_t maxIndex = count ? *std::max_element(indices, indices + count) : 0;
  std::vector<uint8_t> bytes(meshopt_encodeIndexBufferBound(count, size_t{maxIndex} + 1));
  bytes.resize(meshopt_encodeIndexBuffer(bytes.data(), bytes.size(), indices, count));
  return bytes;
}

}  // namespace

std::vector<uint8_t> encodeVertexStream(const void* records, size_t count, size_t stride) {
  pinEncoderVersions();
  std::vector<uint8_t> bytes(meshopt_encodeVertexBufferBound(count, stride));
  bytes.resize(meshopt_encodeVertexBuffer(bytes.data(), bytes.size(), records, count, stride));
  return bytes;
}

EncodedIndices encodeIndexStream(const uint32_t* indices, size_t count) {
  EncodedIndices out;
  if (count % 3 == 0) {
    out.bytes = encodeTriangles(indices, count);
    const std::vector<uint32_t> back = decodeTriangles(out.bytes, count);
    if (back.size() == count && std::equal(back.begin(), back.end(), indices)) {
      out.codec = kIndexCodecTriangles;
      return out;
    }
  }
  pinEncoderVersions();
  const uint32_t maxIndex = count ? *std::max_element(indices, indices + count) : 0;
  out.bytes.assign(meshopt_encodeIndexSequenceBound(count, size_t{maxIndex} + 1), 0);
  out.bytes.resize(meshopt_encodeIndexSequence(out.bytes.data(), out.bytes.size(), indices, count));
  std::vector<uint32_t> back(count);
  if (meshopt_decodeIndexSequence(back.data(), count, sizeof(uint32_t), out.bytes.data(), out.bytes.size()) == 0 &&
      std::equal(back.begin(), back.end(), indices)) {
    out.codec = kIndexCodecSequence;
    return out;
  }
  out.bytes.resize(count * sizeof(uint32_t));
  if (count) std::memcpy(out.bytes.data(), indices, out.bytes.size());
  out.codec = kIndexCodecRaw;
  return out;
}

// Whether every triangle of `b` is a rotation of the same triangle of `a` (same vertices, same winding).
bool sameTrianglesRotated(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  if (a.size() != b.size()) return false;
  for (size_t t = 0; t < a.size(); t += 3) {
    bool same = false;
    for (size_t r = 0; r < 3 && !same; ++r)
      same = b[t] == a[t + r] && b[t + 1] == a[t + (r + 1) % 3] && b[t + 2] == a[t + (r + 2) % 3];
    if (!same) return false;
  }
  return true;
}

bool rotateTrianglesToCodecOrder(std::vector<uint32_t>& indices) {
  if (indices.empty() || indices.size() % 3 != 0) return false;
  std::vector<uint32_t> current = indices;
  for (int pass = 0; pass < 4; ++pass) {
    std::vector<uint32_t> next = decodeTriangles(encodeTriangles(current.data(), current.size()), current.size());
    // The codec's deltas wrap for very large index jumps: anything but a rotation leaves the mesh as it was.
    if (!sameTrianglesRotated(indices, next)) return false;
    if (next == current) {
      indices = std::move(current);
      return true;
    }
    current = std::move(next);
  }
  return false;
}

std::string decodeVertexStream(void* out, size_t count, size_t stride, const uint8_t* data, size_t size) {
  // The decoder asserts on these instead of failing: check them first.
  if (stride == 0 || stride > 256 || stride % 4 != 0) return "unsupported record size " + std::to_string(stride);
  const int rc = meshopt_decodeVertexBuffer(out, count, stride, data, size);
  return rc == 0 ? std::string() : codecError(rc);
}

std::string decodeIndexStream(uint32_t* out, size_t count, uint32_t codec, const uint8_t* data, size_t size) {
  int rc = 0;
  if (codec == kIndexCodecTriangles) {
    if (count % 3 != 0) return "the triangle codec needs a multiple of 3 indices, not " + std::to_string(count);
    rc = meshopt_decodeIndexBuffer(out, count, sizeof(uint32_t), data, size);
  } else if (codec == kIndexCodecSequence) {
    rc = meshopt_decodeIndexSequence(out, count, sizeof(uint32_t), data, size);
  } else if (codec == kIndexCodecRaw) {
    if (size != count * sizeof(uint32_t))
      return "a raw index stream of " + std::to_string(size) + " bytes does not hold " + std::to_string(count) +
             " indices";
    if (count) std::memcpy(out, data, size);
  } else {
    return "unknown index codec " + std::to_string(codec);
  }
  return rc == 0 ? std::string() : codecError(rc);
}

}  // namespace visbuf::pack

// ---------------------------------------------------------------------------------------------------------
// The pack reader's geometry (pack_parser.h): meshes, LODs and their encoded vertex and index streams, and the
// optional per-mesh streams (tangents, second uv set).

namespace visbuf::pack_detail {

namespace {

// The most a codec can expand its input: the vertex codec spends at least 2 bits per 16 decoded bytes (64x), the
// triangle codec one byte per triangle (12 decoded bytes), the sequence codec one byte per index (4). Checking a
// stream's declared decoded size against these before allocating keeps a hostile pack from making the reader
// allocate more than 64 times the file's size.
constexpr uint64_t kVertexCodecMaxExpansion = 64;
constexpr uint64_t kTriangleCodecMaxExpansion = 12;
constexpr uint64_t kSequenceCodecMaxExpansion = 4;

bool expansionFits(uint64_t decodedBytes, uint64_t encodedBytes, uint64_t factor) {
  return encodedBytes <= std::numeric_limits<uint64_t>::max() / factor && decodedBytes <= encodedBytes * factor;
}

}  // namespace

Status Parser::decodeVertices(void* out, uint64_t count, size_t stride, const SectionView& section, uint64_t byte,
                              uint64_t bytes, const std::string& where) const {
  if (!rangeFits(byte, bytes, section.entry.size))
    return fail(fmt::format("{}: encoded bytes [{}, {} + {}) lie outside section '{}' ({} bytes)", where, byte, byte,
                            bytes, section.name, section.entry.size));
  if (!expansionFits(count * stride, bytes, kVertexCodecMaxExpansion))
    return fail(fmt::format("{}: {} bytes cannot encode {} records of {} bytes (the codec expands at most {}x)",
                            where, bytes, count, stride, kVertexCodecMaxExpansion));
  const std::string why = pack::decodeVertexStream(out, count, stride, section.data + byte, bytes);
  if (!why.empty())
    return fail(fmt::format("{}: the encoded stream in section '{}' (bytes [{}, {} + {})) does not decode to {} "
                            "records: {}", where, section.name, byte, byte, bytes, count, why));
  return {};
}

Status Parser::readMeshes(Scene* scene) {
  const SectionView& meshes = sections_.at(pack::kMeshesSection);
  const SectionView& lods = sections_.at(pack::kLodsSection);
  const bool quantized = sections_.count(pack::kQVerticesSection) != 0;
  const SectionView& vertices = sections_.at(quantized ? pack::kQVerticesSection : pack::kVerticesSection);
  const SectionView quantization = optional(pack::kQuantizationSection);
  const SectionView& indices = sections_.at(pack::kIndicesSection);
  const SectionView& encoding = sections_.at(pack::kMeshEncodingSection);
  if (meshes.entry.count == 0) return fail("section 'meshes' is empty: a pack needs at least one mesh");
  if (quantized && quantization.entry.count != meshes.entry.count) {
    return fail(fmt::format("section 'quantization' has {} records for {} meshes", quantization.entry.count,
                            meshes.entry.count));
  }
  if (encoding.entry.count != meshes.entry.count)
    return fail(fmt::format("section 'meshEncoding' has {} records for {} meshes", encoding.entry.count,
                            meshes.entry.count));
  scene->meshes.reserve(meshes.entry.count);
  uint64_t vertexTotal = 0, indexTotal = 0;  // the decoded streams so far
  for (uint64_t i = 0; i < meshes.entry.count; ++i) {
    const auto r = record<pack::MeshRecord>(meshes, i);
    std::string where = fmt::format("section 'meshes' record {}", i);
    auto name = string(r.name, where + " field 'name'");
    if (!name) return name.error();
    where += " ('" + *name + "')";
    auto outside = [&](const char* first, uint64_t firstValue, const char* count, uint64_t countValue,
                       const SectionView& target) {
      return fail(fmt::format("{}: fields '{}' {} + '{}' {} run past the {} records of section '{}'", where,
                              first, firstValue, count, countValue, target.entry.count, target.name));
    };
    if (r.vertexCount == 0 || r.indexCount < 3) {
      return fail(fmt::format("{}: 'vertexCount' {} / 'indexCount' {} (need >= 1 / >= 3)", where,
                              r.vertexCount, r.indexCount));
    }
    if (r.firstVertex != vertexTotal || r.firstIndex != indexTotal)
      return fail(fmt::format("{}: fields 'firstVertex' {} / 'firstIndex' {} must be {} / {}, the counts of the "
                              "meshes before it", where, r.firstVertex, r.firstIndex, vertexTotal, indexTotal));
    vertexTotal += r.vertexCount;
    indexTotal += r.indexCount;
    if (r.lodCount == 0 || r.lodCount > MAX_LODS)
      return fail(fmt::format("{}: field 'lodCount' is {} (1..{})", where, r.lodCount, MAX_LODS));
    if (!rangeFits(r.firstLod, r.lodCount, lods.entry.count))
      return outside("firstLod", r.firstLod, "lodCount", r.lodCount, lods);
    if (!allFinite(r.boundsSphere, 4) || r.boundsSphere[3] < 0.0f)
      return fail(fmt::format("{}: field 'boundsSphere' is not finite with a radius >= 0", where));

    const auto e = record<pack::MeshEncodingRecord>(encoding, i);
    const std::string ew = fmt::format("section 'meshEncoding' record {} (mesh '{}')", i, *name);
    if (e.vertexCount != r.vertexCount || e.indexCount != r.indexCount)
      return fail(fmt::format("{}: its streams decode to {} vertices / {} indices, but the mesh record has {} / {}",
                              ew, e.vertexCount, e.indexCount, r.vertexCount, r.indexCount));
    if (e.reserved != 0) return fail(fmt::format("{}: field 'reserved' is {}, expected 0", ew, e.reserved));
    if (e.indexCodec != pack::kIndexCodecTriangles && e.indexCodec != pack::kIndexCodecSequence &&
        e.indexCodec != pack::kIndexCodecRaw)
      return fail(fmt::format("{}: field 'indexCodec' is {} (0 triangles, 1 sequence, 2 raw)", ew, e.indexCodec));
    if (!rangeFits(e.indexByte, e.indexBytes, indices.entry.size))
      return fail(fmt::format("{}: encoded index bytes [{}, {} + {}) lie outside section 'indices' ({} bytes)", ew,
                              e.indexByte, e.indexByte, e.indexBytes, indices.entry.size));
    const uint64_t indexExpansion = e.indexCodec == pack::kIndexCodecTriangles ? kTriangleCodecMaxExpansion
                                    : e.indexCodec == pack::kIndexCodecSequence ? kSequenceCodecMaxExpansion
                                                                                : 1;
    if (!expansionFits(uint64_t{r.indexCount} * sizeof(uint32_t), e.indexBytes, indexExpansion))
      return fail(fmt::format("{}: {} bytes cannot encode {} indices (the codec expands at most {}x)", ew,
                              e.indexBytes, r.indexCount, indexExpansion));

    Mesh mesh;
    mesh.name = *name;
    mesh.boundsSphere = glm::vec4(r.boundsSphere[0], r.boundsSphere[1], r.boundsSphere[2], r.boundsSphere[3]);
    const size_t vertexStride = quantized ? sizeof(pack::QVertexRecord) : sizeof(gpu::Vertex);
    // Both checked before any allocation: the range inside the section and the codec's largest expansion.
    if (!rangeFits(e.vertexByte, e.vertexBytes, vertices.entry.size) ||
        !expansionFits(uint64_t{r.vertexCount} * vertexStride, e.vertexBytes, kVertexCodecMaxExpansion))
      return decodeVertices(nullptr, r.vertexCount, vertexStride, vertices, e.vertexByte, e.vertexBytes,
                            ew + " vertices");
    mesh.vertices.resize(r.vertexCount);
    if (quantized) {
      std::vector<pack::QVertexRecord> decoded(r.vertexCount);
      noteScratch(decoded.size() * sizeof(pack::QVertexRecord));
      if (Status st = decodeVertices(decoded.data(), r.vertexCount, vertexStride, vertices, e.vertexByte,
                                     e.vertexBytes, ew + " vertices");
          !st)
        return st;
      const auto q = record<pack::QuantizationRecord>(quantization, i);
      const std::string qw = fmt::format("section 'quantization' record {}", i);
      if (!allFinite(q.positionOffset, 3) || !allFinite(q.uvOffset, 2))
        return fail(qw + ": field 'positionOffset' or 'uvOffset' is not finite");
      auto scaleOk = [](const float* scale, int n) {
        return allFinite(scale, n) && std::all_of(scale, scale + n, [](float x) { return x >= 0.0f; });
      };
      if (!scaleOk(q.positionScale, 3) || !scaleOk(q.uvScale, 2))
        return fail(qw + ": field 'positionScale' or 'uvScale' is not a finite value >= 0");
      for (uint32_t v = 0; v < r.vertexCount; ++v) {
        const pack::QVertexRecord& qv = decoded[v];
        if (qv.reserved != 0) {
          return fail(fmt::format("section 'qvertices' (mesh {} vertex {}): field 'reserved' is {}, expected 0", i,
                                  v, qv.reserved));
        }
        mesh.vertices[v] = pack::dequantizeVertex(q, qv);
      }
    } else if (Status st = decodeVertices(mesh.vertices.data(), r.vertexCount, vertexStride, vertices, e.vertexByte,
                                          e.vertexBytes, ew + " vertices");
               !st) {
      return st;
    }
    mesh.indices.resize(r.indexCount);
    if (const std::string why = pack::decodeIndexStream(mesh.indices.data(), r.indexCount, e.indexCodec,
                                                        indices.data + e.indexByte, e.indexBytes);
        !why.empty())
      return fail(fmt::format("{} indices: the encoded stream in section 'indices' (bytes [{}, {} + {})) does not "
                              "decode to {} indices: {}", ew, e.indexByte, e.indexByte, e.indexBytes, r.indexCount,
                              why));
    // Culling is only conservative if the sphere really contains the mesh: check it (relative slack as in
    // buildMesh's padding, plus float rounding of the distance).
    const glm::dvec3 centre(mesh.boundsSphere);
    const double radius = double(mesh.boundsSphere.w) * (1.0 + 1e-4) + 1e-5;
    for (uint32_t v = 0; v < r.vertexCount; ++v) {
      const gpu::Vertex& vx = mesh.vertices[v];
      if (!std::isfinite(vx.px) || !std::isfinite(vx.py) || !std::isfinite(vx.pz) || !std::isfinite(vx.u) ||
          !std::isfinite(vx.v)) {
        return fail(fmt::format("{}: vertex {} has a non-finite position or texture coordinate", where, v));
      }
      if (glm::length(glm::dvec3(vx.px, vx.py, vx.pz) - centre) > radius)
        return fail(fmt::format("{}: vertex {} lies outside field 'boundsSphere'", where, v));
    }
    for (uint32_t k = 0; k < r.indexCount; ++k) {
      if (mesh.indices[k] >= r.vertexCount) {
        return fail(fmt::format("{}: index {} has value {}, not below 'vertexCount' {}", where, k,
                                mesh.indices[k], r.vertexCount));
      }
    }
    for (uint32_t l = 0; l < r.lodCount; ++l) {
      const auto lr = record<pack::LodRecord>(lods, uint64_t{r.firstLod} + l);
      const std::string lw =
          fmt::format("{} LOD {} (section 'lods' record {})", where, l, uint64_t{r.firstLod} + l);
      if (lr.indexCount == 0 || lr.indexCount % 3 != 0)
        return fail(
            fmt::format("{}: field 'indexCount' {} is not a positive multiple of 3", lw, lr.indexCount));
      if (!rangeFits(lr.firstIndex, lr.indexCount, r.indexCount)) {
        return fail(fmt::format("{}: fields 'firstIndex' {} + 'indexCount' {} run past the mesh's {} indices",
                                lw, lr.firstIndex, lr.indexCount, r.indexCount));
      }
      if (!std::isfinite(lr.error) || lr.error < 0.0f)
        return fail(fmt::format("{}: field 'error' {} is not a finite value >= 0", lw, lr.error));
      mesh.lods.push_back({lr.firstIndex, lr.indexCount, lr.error});
    }
    scene->meshes.push_back(std::move(mesh));
  }
  return {};
}
Status Parser::readMeshStreams(Scene* scene) {
  const SectionView s = optional(pack::kMeshStreamsSection);
  const SectionView tangents = optional(pack::kTangentsSection);
  const SectionView uvs1 = optional(pack::kUvs1Section);
  if (s.data == nullptr && (tangents.data != nullptr || uvs1.data != nullptr))
    return fail("sections 'tangents' / 'uvs1' need section 'meshStreams'");
  if (s.data == nullptr) return {};
  if (s.entry.count != scene->meshes.size())
    return fail(fmt::format("section 'meshStreams' has {} records for {} meshes", s.entry.count, scene->meshes.size()));
  for (uint64_t i = 0; i < s.entry.count; ++i) {
    const auto r = record<pack::MeshStreamsRecord>(s, i);
    Mesh& mesh = scene->meshes[i];
    const uint64_t n = mesh.vertices.size();
    const std::string where = fmt::format("section 'meshStreams' record {}", i);
    if ((r.tangentByte == pack::kNoStream && r.tangentBytes != 0) || (r.uv1Byte == pack::kNoStream && r.uv1Bytes != 0))
      return fail(where + ": a stream marked absent (kNoStream) has a non-zero byte count");
    // Range and expansion checked by decodeVertices() before the allocation: a failed check leaves nothing.
    auto fits = [&](uint64_t byte, uint64_t bytes, const SectionView& section, size_t stride) {
      return rangeFits(byte, bytes, section.entry.size) &&
             expansionFits(n * stride, bytes, kVertexCodecMaxExpansion);
    };
    if (r.tangentByte != pack::kNoStream) {
      const std::string tw = where + " ('" + mesh.name + "') tangents";
      if (!fits(r.tangentByte, r.tangentBytes, tangents, sizeof(glm::vec4)))
        return decodeVertices(nullptr, n, sizeof(glm::vec4), tangents, r.tangentByte, r.tangentBytes, tw);
      mesh.tangents.resize(n);
      if (Status st = decodeVertices(mesh.tangents.data(), n, sizeof(glm::vec4), tangents, r.tangentByte,
                                     r.tangentBytes, tw);
          !st)
        return st;
      for (uint64_t v = 0; v < n; ++v) {
        const glm::vec4 t = mesh.tangents[v];
        const float len = glm::length(glm::vec3(t));
        const bool none = t == glm::vec4(0.0f);
        if (!none && !(std::abs(len - 1.0f) < 1e-2f && (t.w == 1.0f || t.w == -1.0f)))
          return fail(
              fmt::format("{}: tangent of vertex {} is not a unit vector with w = +-1 (or all zero)", where, v));
      }
    }
    if (r.uv1Byte != pack::kNoStream) {
      const std::string uw = where + " ('" + mesh.name + "') uvs1";
      if (!fits(r.uv1Byte, r.uv1Bytes, uvs1, sizeof(glm::vec2)))
        return decodeVertices(nullptr, n, sizeof(glm::vec2), uvs1, r.uv1Byte, r.uv1Bytes, uw);
      mesh.uvs1.resize(n);
      if (Status st = decodeVertices(mesh.uvs1.data(), n, sizeof(glm::vec2), uvs1, r.uv1Byte, r.uv1Bytes, uw); !st)
        return st;
      for (const glm::vec2& uv : mesh.uvs1)
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return fail(where + ": non-finite uv1");
    }
  }
  return {};
}

}  // namespace visbuf::pack_detail
