// glTF importer (gltf_import.h): EXT_mesh_gpu_instancing, a node's per-instance TRS attributes.

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

#include "visbuf/asset/gltf_detail.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf::gltf_detail {

Result<std::vector<glm::dmat4>> Importer::meshInstances(int nodeIndex, const glm::dmat4& world, bool sceneImport) {
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  auto ext = node.extensions.find(kInstancingExt);
  if (ext == node.extensions.end()) return std::vector<glm::dmat4>{world};
  const std::string where = path_ + ": node " + str(nodeIndex) + named(node.name) + " " + kInstancingExt;
  // A mesh index that does not exist is reported by nodeMesh (emitNode / emitSceneMesh), with the node.
  if (node.mesh >= 0 && static_cast<size_t>(node.mesh) >= model_.meshes.size()) return std::vector<glm::dmat4>{world};
  // The extension instances a mesh; on a node without one it has nothing to instance.
  if (node.mesh < 0) {
    warn(where + ": the node has no mesh; extension ignored");
    return std::vector<glm::dmat4>{world};
  }
  // Skinned and animated nodes are placed by their joints or by the node's animated global matrix, which have no
  // place for a per-instance transform: such a node is imported once, as the extension's fallback (the plain
  // node).
  const bool animated = node.skin >= 0 || (sceneImport && (movingNodes_.count(nodeIndex) > 0 ||
                                                           morphAnimatedNodes_.count(nodeIndex) > 0));
  if (animated) {
    const std::string why = "instancing a skinned or animated node is not supported";
    if (instancingRequired_) return makeError(ErrorCode::Unsupported, where + ": " + why);
    warn(where + ": " + why + "; the node is imported once, without its instances");
    return std::vector<glm::dmat4>{world};
  }
  if (!ext->second.IsObject() || !ext->second.Get("attributes").IsObject())
    return malformed(where + ": 'attributes' must be an object");
  const tinygltf::Value& attributes = ext->second.Get("attributes");
  struct Stream {
    const char* semantic;
    AttributeKind kind;
    int components;
    std::vector<float> values;
    int accessor = -1;
  };
  Stream streams[3] = {{"TRANSLATION", AttributeKind::InstanceVec3, 3, {}},
                       {"ROTATION", AttributeKind::InstanceRotation, 4, {}},
                       {"SCALE", AttributeKind::InstanceVec3, 3, {}}};
  std::optional<uint64_t> count;
  int countAccessor = -1;
  const char* countSemantic = "";
  for (Stream& st : streams) {
    if (!attributes.Has(st.semantic)) continue;
    const tinygltf::Value& index = attributes.Get(st.semantic);
    if (!index.IsNumber()) return malformed(where + ": attribute " + st.semantic + " is not an accessor index");
    st.accessor = indexValue(index, model_.accessors.size());
    if (st.accessor < 0)
      return malformed(where + " accessor " + numberText(index) + " (" + st.semantic + "): accessor does not exist");
    const std::string aw = where + " accessor " + str(st.accessor) + " (" + st.semantic + ")";
    const uint64_t n = model_.accessors[static_cast<size_t>(st.accessor)].count;
    if (n == 0 || n > kMaxInstancesPerNode)
      return malformed(aw + ": instance count " + str(n) + " is not in [1, " + str(kMaxInstancesPerNode) + "]");
    // Before anything per instance is decoded or built: within GltfImportOptions::maxInstances (each instance
    // is one object per material group; countInstances counts them as they are emitted).
    if (!count) {
      std::set<int> materials;
      for (const tinygltf::Primitive& p : model_.meshes[static_cast<size_t>(node.mesh)].primitives)
        materials.insert(p.material);
      const uint64_t objects = n * (sceneImport ? materials.size() : 1);
      if (objects > options_.maxInstances - std::min(options_.maxInstances, instancesEmitted_)) {
        return makeError(ErrorCode::CapacityExceeded,
                         aw + ": " + str(n) + " instances" +
                             (objects != n ? " (" + str(objects) + " objects, one per material group)" : "") +
                             " pass the import's limit of " + str(options_.maxInstances) + " instances (" +
                             str(instancesEmitted_) +
                             " so far; raise it with --max-instances, GltfImportOptions::maxInstances)");
      }
    }
    if (count && *count != n)
      return malformed(aw + ": count " + str(n) + " differs from accessor " + str(countAccessor) + " (" +
                       countSemantic + ") count " + str(*count) + " (every instance attribute has one per instance)");
    count = n;
    countAccessor = st.accessor;
    countSemantic = st.semantic;
    int components = 0;
    if (Status s = readFloats(st.accessor, st.kind, aw, &st.values, &components); !s) return s.error();
    for (size_t i = 0; i < st.values.size(); ++i)
      if (!std::isfinite(st.values[i]))
        return malformed(aw + ": instance " + str(uint64_t{i / static_cast<size_t>(st.components)}) +
                         " has a non-finite value (NaN or Inf)");
  }
  if (!count) {  // only custom (underscore) attributes, or none: nothing moves the instances
    warn(where + ": no TRANSLATION, ROTATION or SCALE attribute; the node is imported once");
    return std::vector<glm::dmat4>{world};
  }
  // The transforms here, then (scene import) one ImportedInstance per instance and material group; the
  // flattened import charges its vertex copies in emitPrimitive.
  const uint64_t groups = model_.meshes[static_cast<size_t>(node.mesh)].primitives.size();
  const uint64_t perInstance = sizeof(glm::dmat4) + (sceneImport ? groups * sizeof(ImportedInstance) : 0);
  if (Status s = budget_->charge(*count * perInstance, where); !s) return s.error();
  std::vector<glm::dmat4> out(*count);
  for (uint64_t i = 0; i < *count; ++i) {
    // Each instance's T * R * S, composed like a node's TRS (localMatrix), after the node's world transform.
    glm::dmat3 rs(1.0);
    if (!streams[1].values.empty()) {
      const float* q = &streams[1].values[i * 4];
      const double x = q[0], y = q[1], z = q[2], w = q[3];
      const double len = std::sqrt(x * x + y * y + z * z + w * w);
      if (!(len > 0.0))
        return malformed(where + " accessor " + str(streams[1].accessor) + " (ROTATION): instance " + str(i) +
                         " has a zero-length rotation quaternion");
      rs = quaternionMatrix(x / len, y / len, z / len, w / len);  // exporters write slightly non-unit values
    }
    if (!streams[2].values.empty())
      for (int c = 0; c < 3; ++c) rs[c] *= double(streams[2].values[i * 3 + static_cast<uint64_t>(c)]);
    glm::dmat4 local(rs);
    if (!streams[0].values.empty()) {
      const float* t = &streams[0].values[i * 3];
      local[3] = glm::dvec4(t[0], t[1], t[2], 1.0);
    }
    out[i] = world * local;
    if (!isFinite(out[i]))
      return malformed(where + ": instance " + str(i) + " has a non-finite transform after the node's");
  }
  return out;
}

}  // namespace visbuf::gltf_detail
