// Mesh optimisation and LOD chain (meshoptimizer 0.18): remap/dedup, vertex cache, overdraw, fetch,
// then simplification levels, each simplified from the full mesh so the recorded error is measured
// against the original surface, not accumulated guesswork.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include <fmt/format.h>
#include <meshoptimizer.h>

#include "visbuf/scene/clusters.h"
#include "visbuf/scene/mesh_error.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

namespace {

uint32_t packColor(glm::vec4 c) {
  auto q = [](float v) { return uint32_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
  return q(c.r) | (q(c.g) << 8) | (q(c.b) << 16) | (q(c.a) << 24);
}

// Applies a meshopt remap table (old vertex -> new vertex) to one optional stream; empty stays empty.
template <typename T>
std::vector<T> remapStream(const std::vector<T>& in, const std::vector<uint32_t>& remap, size_t outCount) {
  if (in.empty()) return {};
  std::vector<T> out(outCount);
  meshopt_remapVertexBuffer(out.data(), in.data(), in.size(), sizeof(T), remap.data());
  return out;
}

// Tangents must be finite unit-ish vectors with w = +-1, or all zero ("none for this vertex").
bool validTangent(const glm::vec4& t) {
  if (t == glm::vec4(0.0f)) return true;
  const float len = glm::length(glm::vec3(t));
  return std::isfinite(len) && std::abs(len - 1.0f) < 1e-2f && (t.w == 1.0f || t.w == -1.0f);
}

}  // namespace

uint32_t octEncode(glm::vec3 n) {
  float l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
  if (!(l1 > 0.0f)) return octEncode({0.0f, 0.0f, 1.0f});
  glm::vec2 p(n.x / l1, n.y / l1);
  if (n.z < 0.0f) {
    glm::vec2 s(p.x >= 0.0f ? 1.0f : -1.0f, p.y >= 0.0f ? 1.0f : -1.0f);
    p = (1.0f - glm::abs(glm::vec2(p.y, p.x))) * s;
  }
  auto q = [](float v) { return uint32_t(uint16_t(int16_t(std::lround(std::clamp(v, -1.0f, 1.0f) * 32767.0f)))); };
  return q(p.x) | (q(p.y) << 16);
}

glm::vec3 octDecode(uint32_t packed) {
  auto s = [](uint32_t v) { return std::max(float(int16_t(uint16_t(v))) / 32767.0f, -1.0f); };
  glm::vec2 f(s(packed & 0xFFFF), s(packed >> 16));
  glm::vec3 n(f.x, f.y, 1.0f - std::abs(f.x) - std::abs(f.y));
  float t = std::max(-n.z, 0.0f);
  n.x += n.x >= 0.0f ? -t : t;
  n.y += n.y >= 0.0f ? -t : t;
  return glm::normalize(n);
}

namespace {

// meshopt_simplifySloppy (and simplification across welded seams) may keep, at a corner shared by faces
// with different normals, the vertex of another face: a box's top face would then be lit with the
// front face's normal while its geometry (and so the measured error) is exact. Each corner is moved to
// the vertex at the same position whose normal best matches the triangle's own geometric normal.
void repairCornerAttributes(const std::vector<gpu::Vertex>& vertices, const std::vector<uint32_t>& positionShadow,
                            uint32_t* indices, size_t indexCount) {
  // Group the vertices sharing a position (shadow index = first vertex with that position).
  std::vector<std::vector<uint32_t>> groups(vertices.size());
  for (uint32_t v = 0; v < vertices.size(); ++v) groups[positionShadow[v]].push_back(v);
  auto pos = [&](uint32_t v) { return glm::vec3(vertices[v].px, vertices[v].py, vertices[v].pz); };
  for (size_t t = 0; t + 2 < indexCount; t += 3) {
    glm::vec3 n = glm::cross(pos(indices[t + 1]) - pos(indices[t]), pos(indices[t + 2]) - pos(indices[t]));
    if (!(glm::dot(n, n) > 0.0f)) continue;
    n = glm::normalize(n);
    for (int k = 0; k < 3; ++k) {
      const std::vector<uint32_t>& group = groups[positionShadow[indices[t + k]]];
      if (group.size() < 2) continue;
      uint32_t best = indices[t + k];
      float bestDot = glm::dot(octDecode(vertices[best].normal), n);
      for (uint32_t c : group) {
        float d = glm::dot(octDecode(vertices[c].normal), n);
        if (d > bestDot + 1e-4f) {
          best = c;
          bestDot = d;
        }
      }
      indices[t + k] = best;
    }
  }
}

// The source's JOINTS_0 / WEIGHTS_0 (+ JOINTS_1 / WEIGHTS_1) streams as SkinVertex records (empty when the mesh
// is not skinned), in canonical form: slots with weight 0 get joint 0, so equal influences compare equal byte for
// byte.
Result<std::vector<SkinVertex>> skinVerticesOf(const MeshSource& source) {
  std::vector<SkinVertex> out(source.joints.size());
  const bool second = !source.joints1.empty();
  for (size_t v = 0; v < out.size(); ++v) {
    for (int i = 0; i < kSkinInfluences; ++i) {
      if (i >= 4 && !second) break;
      const float w = i < 4 ? source.weights[v][i] : source.weights1[v][i - 4];
      if (!std::isfinite(w) || w < 0.0f)
        return makeError(ErrorCode::MalformedInput,
                         fmt::format("mesh '{}': vertex {} has skin weight {} (< 0 or not finite)", source.name, v, w));
      out[v].weights[i] = w;
      out[v].joints[i] = w > 0.0f ? (i < 4 ? source.joints[v][i] : source.joints1[v][i - 4]) : uint16_t{0};
    }
  }
  return out;
}

// The source's morph targets as one MorphDelta stream per target (vertexCount each, absent attributes 0).
Result<std::vector<std::vector<gpu::MorphDelta>>> morphStreamsOf(const MeshSource& source) {
  const size_t n = source.positions.size();
  std::vector<std::vector<gpu::MorphDelta>> out(source.morphTargets.size());
  if (!source.morphWeights.empty() && source.morphWeights.size() != source.morphTargets.size())
    return makeError(ErrorCode::MalformedInput, fmt::format("mesh '{}': {} morph weights for {} targets", source.name,
                                                            source.morphWeights.size(), source.morphTargets.size()));
  for (size_t t = 0; t < out.size(); ++t) {
    const MeshSource::MorphTarget& target = source.morphTargets[t];
    for (const std::vector<glm::vec3>* stream : {&target.positions, &target.normals, &target.tangents})
      if (!stream->empty() && stream->size() != n)
        return makeError(ErrorCode::MalformedInput,
                         fmt::format("mesh '{}': morph target {} has {} deltas for {} vertices", source.name, t,
                                     stream->size(), n));
    out[t].assign(n, gpu::MorphDelta{});
    for (size_t v = 0; v < n; ++v) {
      gpu::MorphDelta& d = out[t][v];
      if (!target.positions.empty()) d.px = target.positions[v].x, d.py = target.positions[v].y, d.pz = target.positions[v].z;
      if (!target.normals.empty()) d.nx = target.normals[v].x, d.ny = target.normals[v].y, d.nz = target.normals[v].z;
      if (!target.tangents.empty()) d.tx = target.tangents[v].x, d.ty = target.tangents[v].y, d.tz = target.tangents[v].z;
      for (float f : {d.px, d.py, d.pz, d.nx, d.ny, d.nz, d.tx, d.ty, d.tz})
        if (!std::isfinite(f))
          return makeError(ErrorCode::MalformedInput,
                           fmt::format("mesh '{}': morph target {} vertex {} has a non-finite delta", source.name, t, v));
    }
  }
  return out;
}

}  // namespace

Result<Mesh> buildMesh(const MeshSource& source, const MeshBuildOptions& options) {
  const size_t vertexCount = source.positions.size();
  if (vertexCount == 0 || source.indices.empty() || source.indices.size() % 3 != 0)
    return makeError(ErrorCode::MalformedInput,
                     fmt::format("mesh '{}': needs vertices and a multiple of 3 indices (has {} / {})",
                                 source.name, vertexCount, source.indices.size()));
  if (source.normals.size() != vertexCount || (!source.uvs.empty() && source.uvs.size() != vertexCount) ||
      (!source.colors.empty() && source.colors.size() != vertexCount) ||
      (!source.uvs1.empty() && source.uvs1.size() != vertexCount) ||
      (!source.tangents.empty() && source.tangents.size() != vertexCount) ||
      source.joints.size() != source.weights.size() ||
      (!source.joints.empty() && source.joints.size() != vertexCount) ||
      source.joints1.size() != source.weights1.size() ||
      (!source.joints1.empty() && source.joints1.size() != source.joints.size()))
    return makeError(ErrorCode::MalformedInput, fmt::format("mesh '{}': attribute counts differ", source.name));
  for (uint32_t i : source.indices)
    if (i >= vertexCount)
      return makeError(ErrorCode::MalformedInput,
                       fmt::format("mesh '{}': index {} out of range ({} vertices)", source.name, i, vertexCount));
  for (size_t i = 0; i < vertexCount; ++i) {
    const glm::vec3& p = source.positions[i];
    const glm::vec3& n = source.normals[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(n.x) ||
        !std::isfinite(n.y) || !std::isfinite(n.z))
      return makeError(ErrorCode::MalformedInput,
                       fmt::format("mesh '{}': vertex {} has a non-finite position or normal", source.name, i));
  }

  for (size_t i = 0; i < source.tangents.size(); ++i)
    if (!validTangent(source.tangents[i]))
      return makeError(ErrorCode::MalformedInput,
                       fmt::format("mesh '{}': vertex {} has an invalid tangent (need unit xyz, w = +-1)",
                                   source.name, i));
  for (size_t i = 0; i < source.uvs1.size(); ++i)
    if (!std::isfinite(source.uvs1[i].x) || !std::isfinite(source.uvs1[i].y))
      return makeError(ErrorCode::MalformedInput,
                       fmt::format("mesh '{}': vertex {} has a non-finite uv1", source.name, i));

  // Interleave into the GPU vertex format, then deduplicate vertices identical in every stream.
  std::vector<gpu::Vertex> raw(vertexCount);
  for (size_t i = 0; i < vertexCount; ++i) {
    gpu::Vertex& v = raw[i];
    v.px = source.positions[i].x;
    v.py = source.positions[i].y;
    v.pz = source.positions[i].z;
    v.normal = octEncode(glm::normalize(source.normals[i]));
    v.u = source.uvs.empty() ? 0.0f : source.uvs[i].x;
    v.v = source.uvs.empty() ? 0.0f : source.uvs[i].y;
    v.color = source.colors.empty() ? packColor(glm::vec4(1.0f)) : source.colors[i];
    v.pad = 0;
  }
  Result<std::vector<SkinVertex>> rawSkin = skinVerticesOf(source);
  if (!rawSkin) return rawSkin.error();
  const bool skinned = !rawSkin->empty();
  Result<std::vector<std::vector<gpu::MorphDelta>>> rawMorph = morphStreamsOf(source);
  if (!rawMorph) return rawMorph.error();
  // Deduplicate: two vertices merge only when the GPU vertex, the skin data and every morph delta are identical
  // (vertices that share a rest position but move apart under a target must stay two).
  const size_t indexCount = source.indices.size();
  std::vector<uint32_t> remap(vertexCount);
  std::vector<meshopt_Stream> streams = {{raw.data(), sizeof(gpu::Vertex), sizeof(gpu::Vertex)}};
  if (!source.tangents.empty()) streams.push_back({source.tangents.data(), sizeof(glm::vec4), sizeof(glm::vec4)});
  if (!source.uvs1.empty()) streams.push_back({source.uvs1.data(), sizeof(glm::vec2), sizeof(glm::vec2)});
  if (skinned) streams.push_back({rawSkin->data(), sizeof(SkinVertex), sizeof(SkinVertex)});
  // meshopt_generateVertexRemapMulti takes at most 16 streams: targets beyond that are compared as one key.
  std::vector<uint64_t> morphKey;
  if (rawMorph->size() > 12) {
    morphKey.resize(vertexCount);
    for (size_t v = 0; v < vertexCount; ++v) {
      uint64_t h = 1469598103934665603ull;  // FNV-1a over every delta of the vertex
      for (const auto& target : *rawMorph) {
        const auto* b = reinterpret_cast<const uint8_t*>(&target[v]);
        for (size_t i = 0; i < sizeof(gpu::MorphDelta); ++i) h = (h ^ b[i]) * 1099511628211ull;
      }
      morphKey[v] = h;
    }
    streams.push_back({morphKey.data(), sizeof(uint64_t), sizeof(uint64_t)});
  } else {
    for (const auto& target : *rawMorph)
      streams.push_back({target.data(), sizeof(gpu::MorphDelta), sizeof(gpu::MorphDelta)});
  }
  size_t unique = meshopt_generateVertexRemapMulti(remap.data(), source.indices.data(), indexCount, vertexCount,
                                                   streams.data(), streams.size());
  Mesh mesh;
  mesh.name = source.name;
  mesh.vertices = remapStream(raw, remap, unique);
  mesh.tangents = remapStream(source.tangents, remap, unique);
  mesh.uvs1 = remapStream(source.uvs1, remap, unique);
  mesh.skinVertices = remapStream(*rawSkin, remap, unique);
  std::vector<std::vector<gpu::MorphDelta>> morph(rawMorph->size());
  for (size_t t = 0; t < morph.size(); ++t) morph[t] = remapStream((*rawMorph)[t], remap, unique);
  std::vector<uint32_t> lod0(indexCount);
  meshopt_remapIndexBuffer(lod0.data(), source.indices.data(), indexCount, remap.data());

  const float* pos = &mesh.vertices[0].px;
  const size_t stride = sizeof(gpu::Vertex);
  meshopt_optimizeVertexCache(lod0.data(), lod0.data(), indexCount, unique);
  meshopt_optimizeOverdraw(lod0.data(), lod0.data(), indexCount, pos, unique, stride, 1.05f);
  // Fetch order follows LOD0; coarser levels index a subset of the same vertices. Every vertex is used by
  // LOD0 (the remap above keeps only referenced ones), so the fetch remap is a permutation; one remap reorders
  // every stream so they stay parallel to vertices.
  std::vector<uint32_t> fetch(unique);
  meshopt_optimizeVertexFetchRemap(fetch.data(), lod0.data(), indexCount, unique);
  meshopt_remapIndexBuffer(lod0.data(), lod0.data(), indexCount, fetch.data());
  mesh.vertices = remapStream(mesh.vertices, fetch, unique);
  mesh.tangents = remapStream(mesh.tangents, fetch, unique);
  mesh.uvs1 = remapStream(mesh.uvs1, fetch, unique);
  mesh.skinVertices = remapStream(mesh.skinVertices, fetch, unique);
  // Morph deltas follow the same remaps; the LOD levels below only re-index these vertices, so they share them.
  mesh.morphTargetCount = uint32_t(morph.size());
  mesh.morphDeltas.reserve(morph.size() * unique);
  for (auto& target : morph) {
    target = remapStream(target, fetch, unique);
    mesh.morphDeltas.insert(mesh.morphDeltas.end(), target.begin(), target.end());
  }
  mesh.morphWeights = source.morphWeights;
  if (mesh.morphWeights.empty()) mesh.morphWeights.assign(morph.size(), 0.0f);
  pos = &mesh.vertices[0].px;

  mesh.indices = lod0;
  mesh.lods.push_back({0, uint32_t(indexCount), 0.0f});

  const float scale = meshopt_simplifyScale(pos, unique, stride);
  std::vector<uint32_t> scratch(indexCount);
  // Welding by position + normal: UV/colour seams are borders to meshopt_simplify and stall it early;
  // the shadow index buffer lets coarse levels cross them while vertices whose normals differ (hard
  // edges, e.g. box corners) stay separate, so no level ever borrows another face's normal. Only UV and
  // colour may come from a representative vertex along a crossed seam.
  std::vector<uint32_t> shadow(indexCount);
  static_assert(offsetof(gpu::Vertex, normal) == 12, "position + normal are the first 16 bytes");
  meshopt_generateShadowIndexBuffer(shadow.data(), lod0.data(), indexCount, mesh.vertices.data(), unique,
                                    16, stride);
  // Per vertex: the first vertex with the same position (for repairCornerAttributes).
  std::vector<uint32_t> positionShadow((unique + 2) / 3 * 3);  // the API takes whole triangles
  {
    std::vector<uint32_t> identity(positionShadow.size(), 0);
    for (uint32_t v = 0; v < unique; ++v) identity[v] = v;
    meshopt_generateShadowIndexBuffer(positionShadow.data(), identity.data(), identity.size(), mesh.vertices.data(),
                                      unique, sizeof(float) * 3, stride);
    positionShadow.resize(unique);
  }
  std::vector<glm::vec3> positions(unique);
  for (size_t v = 0; v < unique; ++v) positions[v] = mesh.position(uint32_t(v));
  // The recorded error is the measured two-sided deviation from the full surface (meshoptimizer's estimate,
  // in particular simplifySloppy's, can be far below what the silhouette really loses), never less than the
  // simplifier's own figure; object-space units.
  auto measure = [&](const std::vector<uint32_t>& level, size_t count, float estimate) {
    double measured = measureSimplificationError(positions, lod0, std::span(level.data(), count));
    return std::max(float(measured), estimate * scale);
  };
  std::vector<uint32_t> sloppy(indexCount);
  size_t previous = indexCount;
  float previousError = 0.0f;
  while (mesh.lods.size() < options.maxLods && previous / 3 > options.minTriangles) {
    const double ratio = previous / 3 > options.fineBelowTriangles ? options.lodRatio : options.fineLodRatio;
    size_t target = std::max<size_t>(size_t(double(previous / 3) * ratio) * 3, size_t(options.minTriangles) * 3);
    float err = 0.0f;
    size_t count = meshopt_simplify(scratch.data(), lod0.data(), indexCount, pos, unique, stride, target, 1.0f, 0,
                                    &err);
    if (count > previous * options.minReduction) {
      count = meshopt_simplify(scratch.data(), shadow.data(), indexCount, pos, unique, stride, target, 1.0f, 0, &err);
    }
    const bool stalled = count == 0 || count > previous * options.minReduction;
    float error = stalled ? INFINITY : measure(scratch, count, err);
    // Topology-preserving simplification either stalled (small islands, a handle it may not close) or paid
    // for its reduction with a jump in error (the Kitten at 904 triangles: 8x the previous level's error,
    // where the sloppy simplifier loses half as much with fewer triangles): try meshopt_simplifySloppy too
    // and keep whichever candidate deviates less from the full surface.
    if (stalled || error > 2.5f * std::max(previousError, 1e-12f)) {
      float sloppyEstimate = 0.0f;
      size_t sloppyCount = meshopt_simplifySloppy(sloppy.data(), lod0.data(), indexCount, pos, unique, stride,
                                                  target, 1.0f, &sloppyEstimate);
      if (sloppyCount > 0 && sloppyCount <= previous * options.minReduction) {
        float sloppyError = measure(sloppy, sloppyCount, sloppyEstimate);
        if (sloppyError < error) {
          std::swap(scratch, sloppy);
          count = sloppyCount;
          error = sloppyError;
        }
      }
    }
    if (!std::isfinite(error)) break;  // no candidate reduces the mesh: the chain ends
    repairCornerAttributes(mesh.vertices, positionShadow, scratch.data(), count);
    meshopt_optimizeVertexCache(scratch.data(), scratch.data(), count, unique);
    if (error <= previousError && mesh.lods.size() > 1) {
      // Fewer triangles for no more error than the previous level: that level would never be chosen (the
      // cull pass takes the coarsest level under the threshold), so this one replaces it.
      mesh.indices.resize(mesh.lods.back().firstIndex);
      mesh.lods.pop_back();
      previousError = mesh.lods.back().error;  // (not the replaced level's: this one may lose less than it did)
    }
    error = std::max(error, previousError);  // non-decreasing along the chain
    mesh.lods.push_back({uint32_t(mesh.indices.size()), uint32_t(count), error});
    mesh.indices.insert(mesh.indices.end(), scratch.begin(), scratch.begin() + std::ptrdiff_t(count));
    previous = count;
    previousError = error;
  }

  // Each level's triangles in meshlet order: the clusters of the cull pass (scene/clusters.h).
  for (const Lod& l : mesh.lods)
    clusterOrder(mesh.indices.data() + l.firstIndex, l.indexCount, pos, unique, stride);

  // Bounding sphere: AABB centre, radius to the farthest vertex, padded by a relative epsilon so the
  // float sphere contains every vertex after rounding.
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (size_t i = 0; i < unique; ++i) {
    lo = glm::min(lo, mesh.position(uint32_t(i)));
    hi = glm::max(hi, mesh.position(uint32_t(i)));
  }
  glm::dvec3 c = (glm::dvec3(lo) + glm::dvec3(hi)) * 0.5;
  double r = 0.0;
  for (size_t i = 0; i < unique; ++i) r = std::max(r, glm::length(glm::dvec3(mesh.position(uint32_t(i))) - c));
  mesh.boundsSphere = glm::vec4(glm::vec3(c), float(r * (1.0 + 1e-5) + 1e-6));
  return mesh;
}

}  // namespace visbuf
