// glTF importer (gltf_import.h): one primitive decoded into local-space arrays (attributes, morph targets,
// skin attributes, triangles), the per-mesh cache, node-local matrices, and the transform + morph of a
// primitive instance into a MeshSource.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/asset/gltf_animation.h"
#include "visbuf/asset/gltf_detail.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf::gltf_detail {

namespace {

// Packs a colour in [0,1] (clamped; NaN -> 0) as RGBA8, R in the low byte.
uint32_t packColor(const float* c, int components) {
  auto unorm8 = [](float v) -> uint32_t {
    if (!(v > 0.0f)) return 0;  // also catches NaN
    if (v >= 1.0f) return 255;
    return static_cast<uint32_t>(std::lround(v * 255.0f));
  };
  const uint32_t a = components == 4 ? unorm8(c[3]) : 255u;
  return unorm8(c[0]) | (unorm8(c[1]) << 8) | (unorm8(c[2]) << 16) | (a << 24);
}

bool allFinite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// Normalises tangents in place and snaps w to +-1. False (nothing usable) when any is non-finite, far from unit
// length (quantisation error is ~1e-4; exporters that write zero tangents for degenerate uvs fail here) or has
// |w| != 1.
bool validateTangents(std::vector<glm::vec4>* tangents) {
  for (glm::vec4& t : *tangents) {
    const float len = glm::length(glm::vec3(t));
    const bool unitish = std::isfinite(len) && std::abs(len - 1.0f) <= 0.1f;
    if (!unitish || !std::isfinite(t.w) || std::abs(std::abs(t.w) - 1.0f) > 0.01f) return false;
    t = glm::vec4(glm::vec3(t) / len, t.w < 0.0f ? -1.0f : 1.0f);
  }
  return true;
}

}  // namespace

std::string fmtCoord(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

bool isFinite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

// A tangent follows the surface like a position difference (the linear part, not the normal matrix). Under a
// mirroring transform cross(normal', tangent') flips relative to the transformed bitangent, so w flips too.
glm::vec4 transformTangent(const glm::dmat3& linear, double det, const glm::vec4& t) {
  if (t.w == 0.0f) return glm::vec4(0.0f);  // "none" marker of a padded vertex
  const glm::dvec3 d = linear * glm::dvec3(t);
  const double len = glm::length(d);
  if (!(len > 0.0) || !std::isfinite(len)) return glm::vec4(0.0f);
  return glm::vec4(glm::vec3(d / len), det < 0.0 ? -t.w : t.w);
}

// The rotation matrix of a unit quaternion (x, y, z, w), glTF's order.
glm::dmat3 quaternionMatrix(double x, double y, double z, double w) {
  return glm::dmat3(1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),   // column 0
                    2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),   // column 1
                    2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y));  // column 2
}

Result<DecodedPrimitive> Importer::decodePrimitive(int meshIndex, int primIndex) {
  const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(meshIndex)];
  const tinygltf::Primitive& prim = mesh.primitives[static_cast<size_t>(primIndex)];
  const std::string where =
      path_ + ": mesh " + str(meshIndex) + named(mesh.name) + " primitive " + str(primIndex);
  auto accessorWhere = [&](int accessor, const std::string& semantic) {
    return where + " accessor " + str(accessor) + " (" + semantic + ")";
  };
  DecodedPrimitive out;

  const int mode = prim.mode;
  if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
      mode != TINYGLTF_MODE_TRIANGLE_FAN) {
    static constexpr const char* kModeNames[] = {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"};
    const std::string name = (mode >= 0 && mode <= 3) ? kModeNames[mode] : "unknown mode " + str(mode);
    warn(where + ": " + name + " primitive skipped (only triangles are imported)");
    out.skipped = true;
    return out;
  }
  auto positionIt = prim.attributes.find("POSITION");
  if (positionIt == prim.attributes.end()) {
    warn(where + ": no POSITION attribute; primitive skipped");
    out.skipped = true;
    return out;
  }
  if (prim.extensions.count(kDracoExt) != 0) {
    if (Status s = decodeDraco(meshIndex, primIndex, where); !s) return s.error();
  }
  const int indicesAccessor = primitiveIndices(meshIndex, primIndex);

  // Vertex attributes. All must have POSITION's count.
  if (Status s = readVec3(positionIt->second, AttributeKind::Position,
                          accessorWhere(positionIt->second, "POSITION"), true, &out.positions);
      !s) {
    return s.error();
  }
  const uint64_t vertexCount = out.positions.size();
  auto checkCount = [&](uint64_t count, int accessor, const std::string& semantic) -> Status {
    if (count == vertexCount) return {};
    return malformed(accessorWhere(accessor, semantic) + ": count " + str(count) +
                     " differs from POSITION count " + str(vertexCount));
  };
  if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end()) {
    const std::string w = accessorWhere(it->second, "NORMAL");
    if (Status s = readVec3(it->second, AttributeKind::Normal, w, true, &out.normals); !s) return s.error();
    if (Status s = checkCount(out.normals.size(), it->second, "NORMAL"); !s) return s.error();
  }
  for (auto [semantic, dst] : {std::pair{"TEXCOORD_0", &out.uvs}, std::pair{"TEXCOORD_1", &out.uvs1}}) {
    auto it = prim.attributes.find(semantic);
    if (it == prim.attributes.end()) continue;
    if (Status s = readTexCoords(it->second, accessorWhere(it->second, semantic), dst); !s) return s.error();
    if (Status s = checkCount(dst->size(), it->second, semantic); !s) return s.error();
  }
  if (auto it = prim.attributes.find("TANGENT"); it != prim.attributes.end()) {
    const std::string w = accessorWhere(it->second, "TANGENT");
    if (Status s = readTangents(it->second, w, &out.tangents); !s) return s.error();
    if (Status s = checkCount(out.tangents.size(), it->second, "TANGENT"); !s) return s.error();
    if (!validateTangents(&out.tangents)) {
      warn(w + ": tangents are not finite unit vectors with w = +-1; dropped (the renderer derives them)");
      out.tangents.clear();
    }
  }
  if (auto it = prim.attributes.find("COLOR_0"); it != prim.attributes.end()) {
    const std::string w = accessorWhere(it->second, "COLOR_0");
    std::vector<float> flat;
    int n = 0;
    if (Status s = readFloats(it->second, AttributeKind::Color, w, &flat, &n); !s) return s.error();
    if (Status s = checkCount(flat.size() / static_cast<uint64_t>(n), it->second, "COLOR_0"); !s)
      return s.error();
    out.colors.resize(vertexCount);
    for (uint64_t i = 0; i < vertexCount; ++i)
      out.colors[i] = packColor(&flat[i * static_cast<uint64_t>(n)], n);
  }
  if (Status s = decodeSkinAttributes(prim, where, &out); !s) return s.error();

  // Morph targets (only POSITION and NORMAL matter for a baked mesh; TANGENT too for an animated one).
  for (size_t t = 0; t < prim.targets.size(); ++t) {
    SharedVec3 deltas[3];
    const std::string target = " target " + str(uint64_t{t});
    static constexpr const char* kSemantics[3] = {"POSITION", "NORMAL", "TANGENT"};
    for (int k = 0; k < 3; ++k) {
      auto it = prim.targets[t].find(kSemantics[k]);
      if (it == prim.targets[t].end()) continue;
      const std::string w = where + target + " accessor " + str(it->second) + " (" + kSemantics[k] + ")";
      auto decoded = morphDeltas(it->second, w);
      if (!decoded) return decoded.error();
      if ((*decoded)->size() != vertexCount) {
        return malformed(w + ": count " + str(uint64_t{(*decoded)->size()}) + " differs from POSITION count " +
                         str(vertexCount));
      }
      deltas[k] = std::move(decoded).value();
    }
    out.positionDeltas.push_back(std::move(deltas[0]));
    out.normalDeltas.push_back(std::move(deltas[1]));
    out.tangentDeltas.push_back(std::move(deltas[2]));
  }

  // Indices: explicit or sequential; then convert the topology to a triangle list.
  std::vector<uint32_t> indices;
  if (indicesAccessor >= 0) {
    const std::string w = accessorWhere(indicesAccessor, "indices");
    if (Status s = readIndices(indicesAccessor, w, &indices); !s) return s.error();
    for (size_t i = 0; i < indices.size(); ++i) {
      if (indices[i] >= vertexCount) {
        return malformed(w + ": index value " + str(uint64_t{indices[i]}) + " at position " +
                         str(uint64_t{i}) + " is not below the vertex count " + str(vertexCount));
      }
    }
  } else {
    if (vertexCount > std::numeric_limits<uint32_t>::max()) {
      return makeError(ErrorCode::CapacityExceeded, where + ": more than 2^32-1 vertices");
    }
    if (Status s = budget_->charge(vertexCount * sizeof(uint32_t), where); !s) return s.error();
    indices.resize(vertexCount);
    for (uint64_t i = 0; i < vertexCount; ++i) indices[i] = static_cast<uint32_t>(i);
  }
  const size_t n = indices.size();
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    if (n % 3 != 0)
      warn(where + ": index count " + str(uint64_t{n}) + " is not a multiple of 3; extra ignored");
    out.triangles.assign(indices.begin(), indices.begin() + static_cast<std::ptrdiff_t>(n - n % 3));
  } else {
    // Strips and fans; triangles that repeat an index are stitching artefacts (strip restarts), so drop them.
    auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
      if (a == b || b == c || a == c) return;
      out.triangles.insert(out.triangles.end(), {a, b, c});
    };
    for (size_t i = 0; i + 2 < n; ++i) {
      if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        // Spec: odd triangles swap their first two vertices to keep a consistent winding.
        if (i % 2 == 0) {
          add(indices[i], indices[i + 1], indices[i + 2]);
        } else {
          add(indices[i + 1], indices[i], indices[i + 2]);
        }
      } else {
        add(indices[i + 1], indices[i + 2], indices[0]);  // spec: fan triangle i = (p[i+1], p[i+2], p[0])
      }
    }
  }
  if (out.triangles.empty()) {
    warn(where + ": no triangles; primitive skipped");
    out.skipped = true;
  }
  return out;
}

// JOINTS_0 + WEIGHTS_0 (both or neither), and JOINTS_1 + WEIGHTS_1 (both or neither, only beside set 0): up to 8
// influences, normalised together. JOINTS_2+ are ignored with a warning (the skinning pass takes 8).
Status Importer::decodeSkinAttributes(const tinygltf::Primitive& prim, const std::string& where,
                                      DecodedPrimitive* out) {
  auto joints = prim.attributes.find("JOINTS_0");
  auto weights = prim.attributes.find("WEIGHTS_0");
  if (joints == prim.attributes.end() && weights == prim.attributes.end()) return {};
  if (joints == prim.attributes.end() || weights == prim.attributes.end()) {
    warn(where + ": JOINTS_0 and WEIGHTS_0 must come together; skinning attributes ignored");
    return {};
  }
  auto joints1 = prim.attributes.find("JOINTS_1");
  auto weights1 = prim.attributes.find("WEIGHTS_1");
  const bool second = joints1 != prim.attributes.end() && weights1 != prim.attributes.end();
  if (!second && (joints1 != prim.attributes.end() || weights1 != prim.attributes.end()))
    return malformed(where + ": JOINTS_1 and WEIGHTS_1 must come together");
  if (prim.attributes.count("JOINTS_2") != 0 || prim.attributes.count("WEIGHTS_2") != 0)
    warn(where + ": JOINTS_2+ / WEIGHTS_2+ ignored (at most 8 influences per vertex); the weights of sets 0 and 1 "
                 "are renormalised without them");
  const int influences = second ? 8 : 4;
  const size_t vertices = out->positions.size();
  // Joint and weight values, `influences` per vertex: set 0's four, then set 1's.
  std::vector<float> flat[2];
  flat[0].resize(vertices * static_cast<size_t>(influences));
  flat[1].resize(vertices * static_cast<size_t>(influences));
  using It = std::map<std::string, int>::const_iterator;
  const std::tuple<It, AttributeKind, int, int> sets[] = {
      {joints, AttributeKind::Joints, 0, 0}, {weights, AttributeKind::Weights, 1, 0},
      {joints1, AttributeKind::Joints, 0, 1}, {weights1, AttributeKind::Weights, 1, 1}};
  for (const auto& [it, kind, k, set] : sets) {
    if (set == 1 && !second) continue;
    const std::string w = where + " accessor " + str(it->second) + " (" + it->first + ")";
    std::vector<float> values;
    int n = 0;
    if (Status s = readFloats(it->second, kind, w, &values, &n); !s) return s;
    if (values.size() != vertices * 4) {
      return malformed(w + ": count " + str(uint64_t{values.size() / 4}) + " differs from POSITION count " +
                       str(uint64_t{vertices}));
    }
    for (size_t v = 0; v < vertices; ++v)
      for (size_t c = 0; c < 4; ++c)
        flat[k][v * static_cast<size_t>(influences) + static_cast<size_t>(set) * 4 + c] = values[v * 4 + c];
  }
  const std::string w = where + " accessor " + str(weights->second) + " (WEIGHTS_0" +
                        (second ? " + WEIGHTS_1 accessor " + str(weights1->second) : std::string()) + ")";
  SkinStreams streams;
  if (Status s = convertSkinAttributes(flat[0], flat[1], influences, w, [this](const std::string& m) { warn(m); },
                                       &streams);
      !s)
    return s;
  out->joints = std::move(streams.joints);
  out->weights = std::move(streams.weights);
  out->joints1 = std::move(streams.joints1);
  out->weights1 = std::move(streams.weights1);
  return {};
}

Result<const std::vector<DecodedPrimitive>*> Importer::decodedMesh(int mesh) {
  auto& slot = meshCache_[static_cast<size_t>(mesh)];
  if (!slot) {
    if (Status s = checkMeshFits(mesh); !s) return s.error();
    std::vector<DecodedPrimitive> prims;
    const size_t count = model_.meshes[static_cast<size_t>(mesh)].primitives.size();
    for (size_t p = 0; p < count; ++p) {
      auto decoded = decodePrimitive(mesh, static_cast<int>(p));
      if (!decoded) return decoded.error();
      prims.push_back(std::move(decoded).value());
    }
    slot = std::move(prims);
  }
  return &*slot;
}

// The node's local transform: `matrix` (column-major) or T * R * S. Non-finite values are an error.
Result<glm::dmat4> Importer::localMatrix(int nodeIndex) {
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  const std::string where = path_ + ": node " + str(nodeIndex) + named(node.name);
  if (!allFinite(node.matrix) || !allFinite(node.translation) || !allFinite(node.rotation) ||
      !allFinite(node.scale)) {
    return malformed(where + ": non-finite transform");
  }
  glm::dmat4 m(1.0);
  if (!node.matrix.empty()) {
    if (node.matrix.size() != 16) return malformed(where + ": matrix must have 16 elements");
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[static_cast<size_t>(c * 4 + r)];
    return m;
  }
  if (!node.translation.empty() && node.translation.size() != 3) {
    return malformed(where + ": translation must have 3 elements");
  }
  if (!node.rotation.empty() && node.rotation.size() != 4)
    return malformed(where + ": rotation must have 4 elements");
  if (!node.scale.empty() && node.scale.size() != 3) return malformed(where + ": scale must have 3 elements");
  glm::dmat3 rs(1.0);
  if (!node.rotation.empty()) {
    // glTF quaternions are (x, y, z, w). Normalise defensively: exporters write slightly non-unit values.
    double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2], w = node.rotation[3];
    const double len = std::sqrt(x * x + y * y + z * z + w * w);
    if (!(len > 0.0) || !std::isfinite(len)) {
      warn(where + ": zero-length or out-of-range rotation quaternion treated as identity");
    } else {
      rs = quaternionMatrix(x / len, y / len, z / len, w / len);
    }
  }
  if (!node.scale.empty()) {
    for (int c = 0; c < 3; ++c) rs[c] *= node.scale[static_cast<size_t>(c)];
  }
  m = glm::dmat4(rs);
  if (!node.translation.empty())
    m[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
  return m;
}

// Appends one primitive instance: morph, transform, winding fix-up, normals.
Status Importer::emitPrimitive(const DecodedPrimitive& prim, const glm::dmat4& world,
                               const std::vector<double>& weights, const std::string& where,
                               MeshSource* out) {
  const size_t base = out->positions.size();
  const size_t count = prim.positions.size();
  if (count > std::numeric_limits<uint32_t>::max() - base) {
    return makeError(ErrorCode::CapacityExceeded, where + ": the scene has more than 2^32-1 vertices");
  }
  const size_t targets = std::min(weights.size(), prim.positionDeltas.size());
  if (weights.size() != prim.positionDeltas.size() && !weights.empty()) {
    warn(where + ": " + str(uint64_t{weights.size()}) + " morph weights for " +
         str(uint64_t{prim.positionDeltas.size()}) + " targets; using the first " + str(uint64_t{targets}));
  }

  // Normals go through the cofactor matrix (= det * inverse-transpose), which also exists for singular
  // matrices; multiplying by sign(det) makes it point like the inverse-transpose.
  const glm::dmat3 linear(world);
  const double det = glm::determinant(linear);
  const glm::dmat3 normalMatrix =
      glm::dmat3(glm::cross(linear[1], linear[2]), glm::cross(linear[2], linear[0]),
                 glm::cross(linear[0], linear[1])) *
      (det < 0.0 ? -1.0 : 1.0);
  const bool flip = det < 0.0;

  // What this primitive instance adds to the output (positions, normals, indices, the optional streams).
  uint64_t perVertex = 2 * sizeof(glm::vec3);
  if (!prim.uvs.empty()) perVertex += sizeof(glm::vec2);
  if (!prim.uvs1.empty()) perVertex += sizeof(glm::vec2);
  if (!prim.colors.empty()) perVertex += sizeof(uint32_t);
  if (!prim.tangents.empty()) perVertex += sizeof(glm::vec4);
  if (!prim.joints.empty()) perVertex += sizeof(glm::u16vec4) + sizeof(glm::vec4);
  if (!prim.joints1.empty()) perVertex += sizeof(glm::u16vec4) + sizeof(glm::vec4);
  if (Status s = budget_->charge(count * perVertex + prim.triangles.size() * sizeof(uint32_t), where); !s) return s;

  // The weighted targets, one term per distinct delta array (targets that share an accessor share the array, so
  // their weights add): the work per vertex is bounded by the distinct accessors, not by the target count.
  auto weighted = [&](const std::vector<SharedVec3>& deltas) {
    std::vector<std::pair<const std::vector<glm::vec3>*, double>> terms;
    std::map<const std::vector<glm::vec3>*, size_t> slot;
    for (size_t t = 0; t < targets; ++t) {
      if (!deltas[t] || weights[t] == 0.0) continue;
      auto [it, added] = slot.emplace(deltas[t].get(), terms.size());
      if (added) terms.emplace_back(deltas[t].get(), 0.0);
      terms[it->second].second += weights[t];
    }
    return terms;
  };
  const auto positionTerms = weighted(prim.positionDeltas);
  const auto normalTerms = weighted(prim.normalDeltas);

  out->positions.resize(base + count);
  out->normals.resize(base + count);
  std::vector<uint8_t> needsNormal(count, prim.normals.empty() ? 1 : 0);
  size_t zeroNormals = 0;
  for (size_t v = 0; v < count; ++v) {
    glm::dvec3 p(prim.positions[v]);
    for (const auto& [delta, w] : positionTerms) p += w * glm::dvec3((*delta)[v]);
    const glm::dvec3 wp = glm::dvec3(world * glm::dvec4(p, 1.0));
    const glm::vec3 fp(wp);
    if (!std::isfinite(fp.x) || !std::isfinite(fp.y) || !std::isfinite(fp.z)) {
      return malformed(where + ": vertex " + str(uint64_t{v}) + " is non-finite after the node transform");
    }
    if (!(std::abs(wp.x) <= kMaxImportCoordinate && std::abs(wp.y) <= kMaxImportCoordinate &&
          std::abs(wp.z) <= kMaxImportCoordinate)) {
      return malformed(where + ": vertex " + str(uint64_t{v}) + " at (" + fmtCoord(wp.x) + ", " + fmtCoord(wp.y) +
                       ", " + fmtCoord(wp.z) + ") is too far from the origin (|coordinate| > " +
                       fmtCoord(kMaxImportCoordinate) + "): its bounds would overflow");
    }
    out->positions[base + v] = fp;
    if (!prim.normals.empty()) {
      glm::dvec3 n(prim.normals[v]);
      for (const auto& [delta, w] : normalTerms) n += w * glm::dvec3((*delta)[v]);
      n = normalMatrix * n;
      const double len = glm::length(n);
      if (len > 0.0 && std::isfinite(len)) {
        out->normals[base + v] = glm::vec3(n / len);
      } else {
        needsNormal[v] = 1;
        ++zeroNormals;
      }
    }
  }

  const size_t firstIndex = out->indices.size();
  out->indices.resize(firstIndex + prim.triangles.size());
  for (size_t i = 0; i < prim.triangles.size(); i += 3) {
    const uint32_t b = static_cast<uint32_t>(base);
    out->indices[firstIndex + i] = b + prim.triangles[i];
    out->indices[firstIndex + i + 1] = b + prim.triangles[flip ? i + 2 : i + 1];
    out->indices[firstIndex + i + 2] = b + prim.triangles[flip ? i + 1 : i + 2];
  }

  // Missing (or unusable) normals: area-weighted vertex normals of this primitive instance, from the final
  // positions and winding. The cross product's length is twice the triangle area, hence the weighting.
  const bool anyNeeded = prim.normals.empty() || zeroNormals > 0;
  if (anyNeeded && options_.generateNormalsIfMissing) {
    std::vector<glm::dvec3> accum(count, glm::dvec3(0.0));
    for (size_t i = firstIndex; i < out->indices.size(); i += 3) {
      const uint32_t a = out->indices[i], b = out->indices[i + 1], c = out->indices[i + 2];
      const glm::dvec3 pa(out->positions[a]), pb(out->positions[b]), pc(out->positions[c]);
      const glm::dvec3 faceNormal = glm::cross(pb - pa, pc - pa);
      accum[a - base] += faceNormal;
      accum[b - base] += faceNormal;
      accum[c - base] += faceNormal;
    }
    for (size_t v = 0; v < count; ++v) {
      if (!needsNormal[v]) continue;
      const double len = glm::length(accum[v]);
      // Vertices used by no (non-degenerate) triangle get an arbitrary unit normal.
      out->normals[base + v] =
          len > 0.0 && std::isfinite(len) ? glm::vec3(accum[v] / len) : glm::vec3(0, 0, 1);
    }
  } else if (anyNeeded && !warnedZeroNormals_) {
    warnedZeroNormals_ = true;
    warn(path_ +
         ": some vertices have no usable normal and generateNormalsIfMissing is off; they get (0,0,0)");
  }
  if (zeroNormals > 0) {
    warn(where + ": " + str(uint64_t{zeroNormals}) + " zero-length normal(s) replaced" +
         (options_.generateNormalsIfMissing ? " by generated normals" : " by (0,0,0)"));
  }

  // Optional attributes: pad earlier primitives with defaults when the first one that has them shows up.
  if (!prim.uvs.empty()) {
    out->uvs.resize(base, glm::vec2(0.0f));
    out->uvs.insert(out->uvs.end(), prim.uvs.begin(), prim.uvs.end());
  }
  if (!prim.colors.empty()) {
    out->colors.resize(base, 0xFFFFFFFFu);
    out->colors.insert(out->colors.end(), prim.colors.begin(), prim.colors.end());
  }
  if (!prim.uvs1.empty()) {
    out->uvs1.resize(base, glm::vec2(0.0f));
    out->uvs1.insert(out->uvs1.end(), prim.uvs1.begin(), prim.uvs1.end());
  }
  if (!prim.tangents.empty()) {
    out->tangents.resize(base, glm::vec4(0.0f));
    for (const glm::vec4& t : prim.tangents) out->tangents.push_back(transformTangent(linear, det, t));
  }
  return {};
}

Result<Importer::NodeMesh> Importer::nodeMesh(int nodeIndex) {
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  NodeMesh out;
  out.where = path_ + ": node " + str(nodeIndex) + named(node.name);
  if (node.mesh < 0) return out;
  if (static_cast<size_t>(node.mesh) >= model_.meshes.size()) {
    return malformed(out.where + ": mesh " + str(node.mesh) + " does not exist");
  }
  out.mesh = &model_.meshes[static_cast<size_t>(node.mesh)];
  auto prims = decodedMesh(node.mesh);
  if (!prims) return prims.error();
  out.prims = *prims;
  out.weights = node.weights.empty() ? &out.mesh->weights : &node.weights;
  if (!allFinite(*out.weights)) return malformed(out.where + ": non-finite morph weights");
  return out;
}

Status Importer::emitNode(int nodeIndex, const glm::dmat4& world, MeshSource* out) {
  auto r = nodeMesh(nodeIndex);  // (the node's mesh, its decoded primitives and weights, and where it is)
  if (!r) return r.error();
  if (!r->mesh) return {};
  if (Status s = countInstances(1, r->where); !s) return s;  // each use is a copy of the mesh's vertices
  const std::string meshWhere =
      r->where + " mesh " + str(model_.nodes[static_cast<size_t>(nodeIndex)].mesh) + named(r->mesh->name);
  for (size_t p = 0; p < r->prims->size(); ++p) {
    const DecodedPrimitive& prim = (*r->prims)[p];
    if (prim.skipped) {
      ++primitivesSkipped;
      continue;
    }
    if (Status s = emitPrimitive(prim, world, *r->weights, meshWhere + " primitive " + str(uint64_t{p}), out); !s)
      return s;
    ++primitivesImported;
  }
  return {};
}

}  // namespace visbuf::gltf_detail
