// glTF importer (gltf_import.h): what an import may ask for before it decodes it. A small file can name one
// large accessor many times (3,000 primitives or 5,000 morph targets sharing it) or ask for millions of
// EXT_mesh_gpu_instancing instances; the checks here refuse those up front, naming the budget, instead of
// charging copy after copy until the budget runs out at its full size.

#include <set>
#include <string>

#include "visbuf/asset/gltf_detail.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf::gltf_detail {

Result<SharedVec3> Importer::morphDeltas(int accessor, const std::string& where) {
  if (auto it = morphDeltaCache_.find(accessor); it != morphDeltaCache_.end()) return it->second;
  auto decoded = std::make_shared<std::vector<glm::vec3>>();
  if (Status s = readVec3(accessor, AttributeKind::MorphDelta, where, true, decoded.get()); !s) return s.error();
  SharedVec3 shared = std::move(decoded);
  morphDeltaCache_.emplace(accessor, shared);
  return shared;
}

// An upper bound of what decodePrimitive() holds for every primitive of the mesh and what emitPrimitive()
// appends for one use of it: each vertex attribute decoded and emitted (normals always emitted: generated when
// missing), indices decoded, converted to triangles and emitted, and each morph target accessor not yet
// decoded (decoded once per import: morphDeltas). Counts come from the accessors as declared; the decode
// itself checks them against the data and charges what it really allocates.
Status Importer::checkMeshFits(int meshIndex) {
  const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(meshIndex)];
  uint64_t total = 0;
  bool overflow = false;
  auto add = [&](uint64_t count, uint64_t bytes) {
    uint64_t product = 0;
    if (!checkedMul(count, bytes, &product) || !checkedAdd(total, product, &total)) overflow = true;
  };
  auto countOf = [&](int accessor) -> uint64_t {
    return accessor >= 0 && static_cast<size_t>(accessor) < model_.accessors.size()
               ? uint64_t{model_.accessors[static_cast<size_t>(accessor)].count}
               : 0;
  };
  struct Attribute {
    const char* semantic;
    uint64_t bytes;  // per vertex, decoded as float (the larger of decoded and emitted)
  };
  static constexpr Attribute kAttributes[] = {
      {"POSITION", sizeof(glm::vec3)}, {"NORMAL", sizeof(glm::vec3)},     {"TEXCOORD_0", sizeof(glm::vec2)},
      {"TEXCOORD_1", sizeof(glm::vec2)}, {"COLOR_0", sizeof(glm::vec4)},  {"TANGENT", sizeof(glm::vec4)},
      {"JOINTS_0", sizeof(glm::vec4)},   {"WEIGHTS_0", sizeof(glm::vec4)}, {"JOINTS_1", sizeof(glm::vec4)},
      {"WEIGHTS_1", sizeof(glm::vec4)}};
  std::set<int> targets;
  for (size_t p = 0; p < mesh.primitives.size(); ++p) {
    const tinygltf::Primitive& prim = mesh.primitives[p];
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        prim.mode != TINYGLTF_MODE_TRIANGLE_FAN)
      continue;
    auto position = prim.attributes.find("POSITION");
    if (position == prim.attributes.end()) continue;
    const uint64_t vertices = countOf(position->second);
    for (const Attribute& a : kAttributes)
      if (auto it = prim.attributes.find(a.semantic); it != prim.attributes.end()) add(countOf(it->second), 2 * a.bytes);
    add(vertices, sizeof(glm::vec3) + sizeof(uint8_t));  // emitted normals and their "needs a normal" flags
    const int indices = primitiveIndices(meshIndex, static_cast<int>(p));
    add(indices >= 0 ? countOf(indices) : vertices, 3 * 3 * sizeof(uint32_t));  // strips: 3 per index
    for (const auto& target : prim.targets)
      for (const auto& [semantic, accessor] : target)
        if (morphDeltaCache_.count(accessor) == 0 && targets.insert(accessor).second)
          add(countOf(accessor), 2 * sizeof(glm::vec3));  // decoded as floats, then as vec3
  }
  if (overflow || total > budget_->remaining()) {
    return makeError(ErrorCode::CapacityExceeded,
                     path_ + ": mesh " + str(meshIndex) + named(mesh.name) + ": its " +
                         str(uint64_t{mesh.primitives.size()}) + " primitives need " +
                         (overflow ? std::string("more than 2^64") : "about " + str(total)) +
                         " bytes decoded and emitted, past the import memory budget of " + str(budget_->limit()) +
                         " bytes (" + str(budget_->used()) +
                         " already used; raise it with --max-import-memory, GltfImportOptions::maxMemoryBytes)");
  }
  return {};
}

Status Importer::countInstances(uint64_t count, const std::string& where) {
  if (count > options_.maxInstances || instancesEmitted_ > options_.maxInstances - count) {
    return makeError(ErrorCode::CapacityExceeded,
                     where + ": " + str(count) + " more mesh instances (" + str(instancesEmitted_) +
                         " so far) pass the import's limit of " + str(options_.maxInstances) +
                         " instances (raise it with --max-instances, GltfImportOptions::maxInstances)");
  }
  instancesEmitted_ += count;
  return {};
}

}  // namespace visbuf::gltf_detail
