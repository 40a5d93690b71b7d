// validateSceneAnimation (scene.h): the animation data of a Scene is consistent with itself and with the
// meshes and objects, so that sampling, skinning and the bounds of skinned objects never index out of range.
#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "scene/animation.h"
#include "scene/scene.h"

namespace visbuf {

namespace {

Error malformed(std::string message) { return makeError(ErrorCode::MalformedInput, std::move(message)); }

// Weights finite, >= 0, summing to 1 (1e-4: float rounding after renormalisation); returns the largest joint
// index with a non-zero weight through `maxJoint` (-1 when there is none).
Status checkSkinVertices(const Mesh& mesh, size_t meshIndex, int64_t* maxJoint) {
  *maxJoint = -1;
  if (mesh.skinVertices.empty()) return {};
  if (mesh.skinVertices.size() != mesh.vertices.size())
    return malformed(fmt::format("mesh {} '{}': {} skin vertices for {} vertices", meshIndex, mesh.name,
                                 mesh.skinVertices.size(), mesh.vertices.size()));
  for (size_t v = 0; v < mesh.skinVertices.size(); ++v) {
    const SkinVertex& s = mesh.skinVertices[v];
    double sum = 0.0;
    for (int i = 0; i < 4; ++i) {
      if (!std::isfinite(s.weights[i]) || s.weights[i] < 0.0f)
        return malformed(fmt::format("mesh {} '{}': skin vertex {} has a negative or non-finite weight",
                                     meshIndex, mesh.name, v));
      sum += s.weights[i];
      if (s.weights[i] > 0.0f) *maxJoint = std::max<int64_t>(*maxJoint, s.joints[i]);
    }
    if (std::abs(sum - 1.0) > 1e-4)
      return malformed(
          fmt::format("mesh {} '{}': skin vertex {} weights sum to {}, not 1", meshIndex, mesh.name, v, sum));
  }
  return {};
}

}  // namespace

Status validateSceneAnimation(const Scene& scene) {
  if (Status s = validateNodes(scene.nodes); !s) return s;
  for (size_t i = 0; i < scene.skins.size(); ++i) {
    const std::string where = fmt::format("skin {} '{}'", i, scene.skins[i].name);
    if (Status s = validateSkin(scene.skins[i], scene.nodes.size(), where); !s) return s;
  }
  for (size_t i = 0; i < scene.animations.size(); ++i) {
    const std::string where = fmt::format("animation {} '{}'", i, scene.animations[i].name);
    if (Status s = validateClip(scene.animations[i], scene.nodes, where); !s) return s;
  }
  std::vector<int64_t> maxJoint(scene.meshes.size(), -1);
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    if (Status s = checkSkinVertices(scene.meshes[m], m, &maxJoint[m]); !s) return s;
  std::vector<uint8_t> seen(scene.objects.size(), 0);
  for (size_t i = 0; i < scene.skinnedObjects.size(); ++i) {
    const SkinnedObject& so = scene.skinnedObjects[i];
    const std::string where = fmt::format("skinned object {}", i);
    if (so.object >= scene.objects.size() || so.skin >= scene.skins.size())
      return malformed(fmt::format("{}: object {} / skin {} out of range ({} objects, {} skins)", where,
                                   so.object, so.skin, scene.objects.size(), scene.skins.size()));
    if (seen[so.object]++) return malformed(fmt::format("{}: object {} is listed twice", where, so.object));
    const uint32_t mesh = scene.objects[so.object].mesh;
    if (scene.meshes[mesh].skinVertices.empty())
      return malformed(
          fmt::format("{}: mesh {} '{}' has no skin vertices", where, mesh, scene.meshes[mesh].name));
    const size_t joints = scene.skins[so.skin].joints.size();
    if (maxJoint[mesh] >= 0 && static_cast<size_t>(maxJoint[mesh]) >= joints)
      return malformed(fmt::format("{}: mesh {} '{}' uses joint index {}, skin {} has {} joints", where, mesh,
                                   scene.meshes[mesh].name, maxJoint[mesh], so.skin, joints));
  }
  return {};
}

std::vector<glm::dmat4> skinnedObjectJoints(const Scene& scene, const SkinnedObject& so, double time) {
  Pose pose = restPose(scene.nodes);
  if (so.clip >= 0 && size_t(so.clip) < scene.animations.size())
    sampleClip(scene.animations[size_t(so.clip)], time + so.timeOffset, true, pose);
  return jointMatrices(scene.skins[so.skin], globalMatrices(scene.nodes, pose));
}

}  // namespace visbuf
