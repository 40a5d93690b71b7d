// Mesh optimisation and LOD chain (meshoptimizer 0.18): remap/dedup, vertex cache, overdraw, fetch,
// then simplification levels, each simplified from the full mesh so the recorded error is measured
// against the original surface, not accumulated guesswork.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

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
// Bounded: the candidates of a position are its vertices with distinct normals, at most kCornerCandidates of them
// (a real corner has a handful; thousands of coincident vertices would make this quadratic), so the work is
// O(indexCount * kCornerCandidates + vertices). Beyond that, a corner picks the best of the first ones.
constexpr size_t kCornerCandidates = 16;

void repairCornerAttributes(const std::vector<gpu::Vertex>& vertices, const std::vector<uint32_t>& positionShadow,
                            uint32_t* indices, size_t indexCount) {
  // Candidates of each position group (shadow index = first vertex with that position), CSR.
  std::vector<uint32_t> start(vertices.size() + 1, 0);
  for (uint32_t v = 0; v < vertices.size(); ++v) start[positionShadow[v] + 1]++;
  for (size_t g = 0; g < vertices.size(); ++g) start[g + 1] = std::min<uint32_t>(start[g + 1], kCornerCandidates);
  for (size_t g = 0; g < vertices.size(); ++g) start[g + 1] += start[g];
  std::vector<uint32_t> size(vertices.size(), 0);
  std::vector<uint32_t> candidates(start.back());
  for (uint32_t v = 0; v < vertices.size(); ++v) {
    const uint32_t g = positionShadow[v];
    const uint32_t capacity = start[g + 1] - start[g];
    if (size[g] == capacity) continue;
    bool repeated = false;  // a normal already offered adds nothing
    for (uint32_t k = 0; k < size[g] && !repeated; ++k)
      repeated = vertices[candidates[start[g] + k]].normal == vertices[v].normal;
    if (!repeated) candidates[start[g] + size[g]++] = v;
  }
  auto pos = [&](uint32_t v) { return glm::vec3(vertices[v].px, vertices[v].py, vertices[v].pz); };
  for (size_t t = 0; t + 2 < indexCount; t += 3) {
    glm::vec3 n = glm::cross(pos(indices[t + 1]) - pos(indices[t]), pos(indices[t + 2]) - pos(indices[t]));
    if (!(glm::dot(n, n) > 0.0f)) continue;
    n = glm::normalize(n);
    for (int k = 0; k < 3; ++k) {
      const uint32_t g = positionShadow[indices[t + k]];
      if (size[g] < 2) continue;
      uint32_t best = indices[t + k];
      float bestDot = glm::dot(octDecode(vertices[best].normal), n);
      for (uint32_t j = start[g]; j < start[g] + size[g]; ++j) {
        const uint32_t c = candidates[j];
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

// meshopt_simplify classifies each vertex by scanning, for every edge, the adjacency of the edge's other end, and
// meshopt_optimizeVertexCache rescans the live triangles of every cached vertex after each triangle it emits: both
// cost about the sum over vertices of valence^2 (a fan of n triangles: n^2). An index list whose sum passes this
// budget (far above any ordinary mesh: ~6 per index) is simplified by clustering only (meshopt_simplifySloppy,
// linear) and ordered with meshopt_optimizeVertexCacheFifo (linear); its levels cost more triangles, never time.
bool valenceWithinBudget(const uint32_t* indices, size_t count, size_t vertexCount, std::vector<uint32_t>& valence) {
  constexpr uint64_t kValenceWorkPerIndex = 256, kValenceWorkFloor = uint64_t{1} << 22;
  valence.assign(vertexCount, 0);
  uint64_t work = 0;
  for (size_t i = 0; i < count; ++i) work += 2 * uint64_t(valence[indices[i]]++) + 1;  // sum of squares, running
  return work <= kValenceWorkPerIndex * count + kValenceWorkFloor;
}

// A simplified level that may join the LOD chain: its indices and measured error (object-space units).
struct LevelCandidate {
  std::vector<uint32_t> indices;
  float error = 0.0f;
};

// Picks at most `budget` of the candidates as the chain's levels after an anchor level (anchorIndices indices,
// anchorError): only candidates on the Pareto front (no other has fewer triangles and no more error), the
// coarsest always, and among them the set that draws the fewest triangles for an instance whose pixel threshold
// is log-uniform: a level is drawn between its own error and the next level's, so it costs its triangles times
// log(next error / its error). Each level keeps at most minReduction of the previous one's triangles. Exact by
// dynamic programming. Returns the indices into `candidates`, finest first.
std::vector<size_t> fineLevels(size_t anchorIndices, float anchorError, const std::vector<LevelCandidate>& candidates,
                               size_t budget, double minReduction) {
  std::vector<size_t> order(candidates.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const auto& ca = candidates[a];
    const auto& cb = candidates[b];
    return ca.indices.size() != cb.indices.size() ? ca.indices.size() < cb.indices.size() : ca.error < cb.error;
  });
  std::vector<size_t> front;  // fewest triangles first, then strictly falling error
  float best = INFINITY;
  for (size_t i : order)
    if (candidates[i].error < best && double(candidates[i].indices.size()) <= double(anchorIndices) * minReduction) {
      front.push_back(i);
      best = candidates[i].error;
    }
  std::reverse(front.begin(), front.end());  // finest first: triangles falling, error rising
  if (front.empty() || budget == 0) return {};
  const size_t n = front.size();
  // Point 0 is the anchor; points 1..n the front. Errors floored so the anchor's log term stays finite.
  std::vector<double> count(n + 1), logError(n + 1);
  const double floor = std::max(double(candidates[front[0]].error) * 0.5, 1e-12);
  count[0] = double(anchorIndices);
  logError[0] = std::log(std::max(double(anchorError), floor));
  for (size_t i = 0; i < n; ++i) {
    count[i + 1] = double(candidates[front[i]].indices.size());
    logError[i + 1] = std::log(std::max(double(candidates[front[i]].error), floor));
  }
  const size_t levels = std::min(budget, n);
  // cost[k][j]: least cost of a chain whose k-th level is point j; from[k][j] the level before it.
  std::vector<std::vector<double>> cost(levels + 1, std::vector<double>(n + 1, INFINITY));
  std::vector<std::vector<size_t>> from(levels + 1, std::vector<size_t>(n + 1, 0));
  cost[0][0] = 0.0;
  for (size_t k = 1; k <= levels; ++k)
    for (size_t j = 1; j <= n; ++j)
      for (size_t i = 0; i < j; ++i) {
        if (!std::isfinite(cost[k - 1][i]) || count[j] > count[i] * minReduction) continue;
        const double c = cost[k - 1][i] + count[i] * (logError[j] - logError[i]);
        if (c < cost[k][j]) {
          cost[k][j] = c;
          from[k][j] = i;
        }
      }
  size_t bestK = 1;
  for (size_t k = 1; k <= levels; ++k)
    if (cost[k][n] < cost[bestK][n]) bestK = k;
  std::vector<size_t> picked;
  for (size_t k = bestK, j = n; k > 0; j = from[k][j], --k) picked.push_back(front[j - 1]);
  std::reverse(picked.begin(), picked.end());
  return picked;
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

  // Lod::indexCount and the index values are 32-bit.
  if (source.indices.size() > std::numeric_limits<uint32_t>::max())
    return makeError(ErrorCode::CapacityExceeded,
                     fmt::format("mesh '{}': {} indices (at most 2^32 - 1 per mesh)", source.name,
                                 source.indices.size()));
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
  // Triangles with two corners at the same place cover no pixel: they are dropped here, before any stage sees
  // them. "The same place" holds in every pose: the same rest position, the same skin influences and the same
  // position delta in every morph target (so a triangle a morph target or a skin opens up is kept). Stacks of such
  // triangles made meshopt_buildMeshlets quadratic (they share one centroid, so its k-d tree degenerates into one
  // leaf scanned for each meshlet), and they only cost draw time. A mesh with nothing else keeps its first triangle
  // (it draws nothing; the mesh stays valid). Work: O(indices * (1 + morph targets)).
  auto samePlace = [&](uint32_t i, uint32_t j) {
    if (i == j) return true;
    if (source.positions[i] != source.positions[j]) return false;
    if (skinned && std::memcmp(&(*rawSkin)[i], &(*rawSkin)[j], sizeof(SkinVertex)) != 0) return false;
    for (const auto& target : *rawMorph)
      if (target[i].px != target[j].px || target[i].py != target[j].py || target[i].pz != target[j].pz) return false;
    return true;
  };
  std::vector<uint32_t> kept;
  kept.reserve(source.indices.size());
  for (size_t t = 0; t + 2 < source.indices.size(); t += 3) {
    const uint32_t a = source.indices[t], b = source.indices[t + 1], c = source.indices[t + 2];
    if (samePlace(a, b) || samePlace(b, c) || samePlace(a, c)) continue;
    kept.insert(kept.end(), {a, b, c});
  }
  if (kept.empty()) kept.assign(source.indices.begin(), source.indices.begin() + 3);
  // A triangle whose corners are at the same places as an earlier kept triangle's, in the same winding, covers the
  // same pixels at the same depths in every pose: only one of them can be seen (which one is z-fighting), and
  // stacks of them (65,600 copies of one triangle) only multiply overdraw. Sorted by their corner positions (each
  // triangle rotated to start at its smallest corner, winding kept), a triangle is dropped when it repeats the
  // first of its run. O(n log n), memory O(kept triangles).
  {
    const size_t tris = kept.size() / 3;
    auto less = [&](uint32_t a, uint32_t b) {
      const glm::vec3 &pa = source.positions[a], &pb = source.positions[b];
      return pa.x != pb.x ? pa.x < pb.x : pa.y != pb.y ? pa.y < pb.y : pa.z < pb.z;
    };
    std::vector<uint8_t> rot(tris);  // the corner each triangle starts at (kept itself is not reordered)
    for (size_t t = 0; t < tris; ++t) {
      const uint32_t* c = &kept[3 * t];
      rot[t] = !less(c[1], c[0]) && !less(c[2], c[0]) ? 0 : (!less(c[2], c[1]) ? 1 : 2);
    }
    auto corner = [&](uint32_t t, int c) { return kept[3 * t + (rot[t] + c) % 3]; };
    std::vector<uint32_t> order(tris);
    for (uint32_t t = 0; t < tris; ++t) order[t] = t;
    auto triLess = [&](uint32_t a, uint32_t b) {
      for (int c = 0; c < 3; ++c) {
        if (less(corner(a, c), corner(b, c))) return true;
        if (less(corner(b, c), corner(a, c))) return false;
      }
      return a < b;  // the earlier triangle first: it is the one kept
    };
    std::sort(order.begin(), order.end(), triLess);
    std::vector<char> drop(tris, 0);
    for (size_t i = 1, first = 0; i < tris; ++i) {
      const uint32_t a = order[first], b = order[i];
      bool samePositions = true, same = true;
      for (int c = 0; c < 3; ++c) {
        samePositions = samePositions && source.positions[corner(a, c)] == source.positions[corner(b, c)];
        same = same && samePositions && samePlace(corner(a, c), corner(b, c));
      }
      if (!samePositions) first = i;  // a new run
      else if (same) drop[b] = 1;      // (same positions, other deformation: kept; it may repeat another kept one)
    }
    size_t out = 0;
    for (size_t t = 0; t < tris; ++t)
      if (!drop[t]) out += 3, std::copy_n(&kept[3 * t], 3, &kept[out - 3]);
    kept.resize(out);
  }
  // Deduplicate: two vertices merge only when the GPU vertex, the skin data and every morph delta are identical
  // (vertices that share a rest position but move apart under a target must stay two).
  const size_t indexCount = kept.size();
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
  // Vertices only the dropped triangles used get no slot (remap ~0u): every vertex left is used by LOD0.
  size_t unique = meshopt_generateVertexRemapMulti(remap.data(), kept.data(), indexCount, vertexCount,
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
  meshopt_remapIndexBuffer(lod0.data(), kept.data(), indexCount, remap.data());

  const float* pos = &mesh.vertices[0].px;
  const size_t stride = sizeof(gpu::Vertex);
  std::vector<uint32_t> valence;
  const bool lod0Bounded = valenceWithinBudget(lod0.data(), indexCount, unique, valence);
  auto optimizeCache = [&](uint32_t* level, size_t count) {
    if (valenceWithinBudget(level, count, unique, valence))
      meshopt_optimizeVertexCache(level, level, count, unique);
    else
      meshopt_optimizeVertexCacheFifo(level, level, count, unique, 16);
  };
  optimizeCache(lod0.data(), indexCount);
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
  // Which index lists meshopt_simplify may take (valenceWithinBudget); the others are simplified by clustering only.
  const bool shadowBounded = lod0Bounded && valenceWithinBudget(shadow.data(), indexCount, unique, valence);
  auto simplify = [&](uint32_t* out, const uint32_t* in, size_t count, bool bounded, size_t target, float* err) {
    if (!bounded && !valenceWithinBudget(in, count, unique, valence)) return size_t{0};
    return meshopt_simplify(out, in, count, pos, unique, stride, target, 1.0f, 0, err);
  };
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
  const TriangleBvh fullTree(positions, lod0);
  auto measure = [&](const std::vector<uint32_t>& level, size_t count, float estimate) {
    double measured = measureSimplificationError(fullTree, positions, lod0, std::span(level.data(), count));
    return std::max(float(measured), estimate * scale);
  };
  std::vector<uint32_t> sloppy(indexCount);
  auto addLevel = [&](std::vector<uint32_t>& level, size_t count, float error) {
    repairCornerAttributes(mesh.vertices, positionShadow, level.data(), count);
    optimizeCache(level.data(), count);
    mesh.lods.push_back({uint32_t(mesh.indices.size()), uint32_t(count), error});
    mesh.indices.insert(mesh.indices.end(), level.begin(), level.begin() + std::ptrdiff_t(count));
  };
  // Coarse levels (above fineBelowTriangles): each aims at lodRatio of the previous one.
  size_t previous = indexCount;
  float previousError = 0.0f;
  while (mesh.lods.size() < options.maxLods && previous / 3 > options.fineBelowTriangles &&
         previous / 3 > options.minTriangles) {
    size_t target = std::max<size_t>(size_t(double(previous / 3) * options.lodRatio) * 3,
                                     size_t(options.minTriangles) * 3);
    float err = 0.0f;
    size_t count = lod0Bounded ? simplify(scratch.data(), lod0.data(), indexCount, true, target, &err) : 0;
    if (shadowBounded && count > previous * options.minReduction)
      count = simplify(scratch.data(), shadow.data(), indexCount, true, target, &err);
    const bool stalled = count == 0 || count > previous * options.minReduction;
    float error = stalled ? INFINITY : measure(scratch, count, err);
    // Topology-preserving simplification either stalled (small islands, a handle it may not close) or paid
    // for its reduction with a jump in error: try meshopt_simplifySloppy too and keep whichever candidate
    // deviates less from the full surface.
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
    if (error <= previousError && mesh.lods.size() > 1) {
      // Fewer triangles for no more error than the previous level: that level would never be chosen (the
      // cull pass takes the coarsest level under the threshold), so this one replaces it.
      mesh.indices.resize(mesh.lods.back().firstIndex);
      mesh.lods.pop_back();
      previousError = mesh.lods.back().error;  // (not the replaced level's: this one may lose less than it did)
    }
    error = std::max(error, previousError);  // non-decreasing along the chain
    addLevel(scratch, count, error);
    previous = count;
    previousError = error;
  }
  // Fine levels (what distant instances draw): a dense sweep of candidates, both simplifiers at each target,
  // measured; the chain takes the levels of the best trade of triangles against error (fineLevels).
  if (mesh.lods.size() < options.maxLods && previous / 3 > options.minTriangles) {
    std::vector<LevelCandidate> candidates;
    auto offer = [&](const std::vector<uint32_t>& level, size_t count, float estimate) {
      if (count > 0 && count < previous)
        candidates.push_back({{level.begin(), level.begin() + std::ptrdiff_t(count)}, measure(level, count, estimate)});
    };
    for (double t = double(previous / 3) * options.fineLodRatio;; t *= options.fineLodRatio) {
      const size_t target = std::max<size_t>(size_t(t), options.minTriangles) * 3;
      float err = 0.0f;
      size_t count = lod0Bounded ? simplify(scratch.data(), lod0.data(), indexCount, true, target, &err) : 0;
      if (shadowBounded && count > target * 2)  // stalled at a seam: let it cross welded seams
        count = simplify(scratch.data(), shadow.data(), indexCount, true, target, &err);
      offer(scratch, count, err);
      float sloppyEstimate = 0.0f;
      size_t sloppyCount = meshopt_simplifySloppy(sloppy.data(), lod0.data(), indexCount, pos, unique, stride,
                                                  target, 1.0f, &sloppyEstimate);
      offer(sloppy, sloppyCount, sloppyEstimate);
      // Clustered (sloppy) at 1.5x and 2.5x the target, then edge collapses down to it: where the topology-preserving
      // simplifier stalls (the Kitten below ~870 triangles), this keeps more of the shape than sloppy alone.
      for (double looser : {1.5, 2.5}) {
        const size_t looseTarget = std::min(size_t(double(target) * looser) / 3 * 3, indexCount);
        if (looseTarget <= target) continue;
        float e1 = 0.0f;
        size_t coarse = meshopt_simplifySloppy(sloppy.data(), lod0.data(), indexCount, pos, unique, stride,
                                               looseTarget, 1.0f, &e1);
        if (coarse <= target) continue;  // (already at the target: the sloppy candidate above)
        float e2 = 0.0f;
        size_t refined = simplify(scratch.data(), sloppy.data(), coarse, false, target, &e2);
        offer(scratch, refined, e1);
      }
      if (target <= size_t(options.minTriangles) * 3) break;
    }
    // A candidate with no more error than the last coarse level and fewer triangles makes that level useless.
    float leastError = INFINITY;
    for (const LevelCandidate& c : candidates) leastError = std::min(leastError, c.error);
    while (mesh.lods.size() > 1 && leastError <= mesh.lods.back().error) {
      mesh.indices.resize(mesh.lods.back().firstIndex);
      mesh.lods.pop_back();
    }
    const float anchorError = mesh.lods.back().error;
    for (LevelCandidate& c : candidates) c.error = std::max(c.error, anchorError);
    for (size_t i : fineLevels(mesh.lods.back().indexCount, anchorError, candidates,
                               options.maxLods - mesh.lods.size(), options.minReduction))
      addLevel(candidates[i].indices, candidates[i].indices.size(), candidates[i].error);
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
