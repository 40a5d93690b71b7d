// validateSceneAnimation (scene.h): the animation data of a Scene is consistent with itself and with the
// meshes and objects, so that sampling, skinning and the bounds of skinned objects never index out of range.
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "visbuf/scene/animation.h"
#include "visbuf/scene/scene.h"

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
    for (int i = 0; i < kSkinInfluences; ++i) {
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

// Deltas: morphTargetCount x vertices, finite; default weights: none or one per target, finite.
Status checkMorphTargets(const Mesh& mesh, size_t meshIndex) {
  const uint64_t expected = uint64_t(mesh.morphTargetCount) * mesh.vertices.size();
  if (mesh.morphDeltas.size() != expected)
    return malformed(fmt::format("mesh {} '{}': {} morph deltas for {} targets x {} vertices", meshIndex,
                                 mesh.name, mesh.morphDeltas.size(), mesh.morphTargetCount, mesh.vertices.size()));
  if (!mesh.morphWeights.empty() && mesh.morphWeights.size() != mesh.morphTargetCount)
    return malformed(fmt::format("mesh {} '{}': {} default morph weights for {} targets", meshIndex, mesh.name,
                                 mesh.morphWeights.size(), mesh.morphTargetCount));
  for (float w : mesh.morphWeights)
    if (!std::isfinite(w)) return malformed(fmt::format("mesh {} '{}': non-finite morph weight", meshIndex, mesh.name));
  for (size_t i = 0; i < mesh.morphDeltas.size(); ++i) {
    const gpu::MorphDelta& d = mesh.morphDeltas[i];
    for (float f : {d.px, d.py, d.pz, d.nx, d.ny, d.nz, d.tx, d.ty, d.tz})
      if (!std::isfinite(f))
        return malformed(fmt::format("mesh {} '{}': morph delta {} (target {}, vertex {}) is not finite", meshIndex,
                                     mesh.name, i, i / mesh.vertices.size(), i % mesh.vertices.size()));
  }
  return {};
}

bool isAffine(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return m[0][3] == 0.0 && m[1][3] == 0.0 && m[2][3] == 0.0 && m[3][3] == 1.0;
}

// Rigid objects: object, node and clip exist, each object at most once and never a skinned object (`seen` marks
// the skinned ones), finite time offset, finite affine placement.
Status validateRigidObjects(const Scene& scene, std::vector<uint8_t>& seen) {
  for (size_t i = 0; i < scene.rigidObjects.size(); ++i) {
    const RigidObject& ro = scene.rigidObjects[i];
    const std::string where = fmt::format("rigid object {}", i);
    if (ro.object >= scene.objects.size())
      return malformed(fmt::format("{}: object {} out of range ({} objects)", where, ro.object, scene.objects.size()));
    if (ro.node < 0 || size_t(ro.node) >= scene.nodes.size())
      return malformed(fmt::format("{}: node {} out of range ({} nodes)", where, ro.node, scene.nodes.size()));
    if (ro.clip < -1 || (ro.clip >= 0 && size_t(ro.clip) >= scene.animations.size()))
      return malformed(fmt::format("{}: clip {} is not -1 or an animation index ({} animations)", where, ro.clip,
                                   scene.animations.size()));
    if (!std::isfinite(ro.timeOffset))
      return malformed(fmt::format("{}: time offset {} is not finite", where, ro.timeOffset));
    if (!isAffine(ro.placement)) return malformed(where + ": placement is not a finite affine matrix");
    if (seen[ro.object]++)
      return malformed(fmt::format("{}: object {} is listed twice (or is also a skinned object)", where, ro.object));
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
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    if (Status s = checkSkinVertices(scene.meshes[m], m, &maxJoint[m]); !s) return s;
    if (Status s = checkMorphTargets(scene.meshes[m], m); !s) return s;
  }
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
    if (so.morphNode < -1 || (so.morphNode >= 0 && size_t(so.morphNode) >= scene.nodes.size()))
      return malformed(fmt::format("{}: morph node {} out of range ({} nodes)", where, so.morphNode,
                                   scene.nodes.size()));
    if (so.morphNode >= 0 && scene.meshes[mesh].morphTargetCount == 0)
      return malformed(fmt::format("{}: morph node {} set, but mesh {} '{}' has no morph targets", where,
                                   so.morphNode, mesh, scene.meshes[mesh].name));
    const size_t joints = scene.skins[so.skin].joints.size();
    if (maxJoint[mesh] >= 0 && static_cast<size_t>(maxJoint[mesh]) >= joints)
      return malformed(fmt::format("{}: mesh {} '{}' uses joint index {}, skin {} has {} joints", where, mesh,
                                   scene.meshes[mesh].name, maxJoint[mesh], so.skin, joints));
  }
  if (Status st = validateRigidObjects(scene, seen); !st) return st;
  return {};
}

std::vector<glm::dmat4> skinnedObjectJoints(const Scene& scene, const SkinnedObject& so, double time) {
  Pose pose = restPose(scene.nodes);
  if (so.clip >= 0 && size_t(so.clip) < scene.animations.size())
    sampleClip(scene.animations[size_t(so.clip)], time + so.timeOffset, true, pose);
  return jointMatrices(scene.skins[so.skin], globalMatrices(scene.nodes, pose));
}

std::vector<double> skinnedObjectMorphWeights(const Scene& scene, const SkinnedObject& so, double time) {
  const Mesh& mesh = scene.meshes[scene.objects[so.object].mesh];
  std::vector<double> weights(mesh.morphTargetCount, 0.0);
  for (size_t t = 0; t < mesh.morphWeights.size() && t < weights.size(); ++t) weights[t] = mesh.morphWeights[t];
  if (so.morphNode < 0) return weights;
  Pose pose = restPose(scene.nodes);
  if (so.clip >= 0 && size_t(so.clip) < scene.animations.size())
    sampleClip(scene.animations[size_t(so.clip)], time + so.timeOffset, true, pose);
  const std::vector<double>& animated = pose.weights[size_t(so.morphNode)];
  for (size_t t = 0; t < animated.size() && t < weights.size(); ++t) weights[t] = animated[t];
  return weights;
}

glm::dmat4 rigidObjectTransform(const Scene& scene, const RigidObject& ro, double time) {
  Pose pose = restPose(scene.nodes);
  if (ro.clip >= 0 && size_t(ro.clip) < scene.animations.size())
    sampleClip(scene.animations[size_t(ro.clip)], time + ro.timeOffset, true, pose);
  return ro.placement * globalMatrices(scene.nodes, pose)[size_t(ro.node)];
}

glm::dmat4 rigidObjectStartTransform(const Scene& scene, const RigidObject& ro, const glm::dmat4& rest) {
  const glm::dmat4 posed = rigidObjectTransform(scene, ro, 0.0);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(posed[c][r])) return rest;
  const double det = glm::determinant(glm::dmat3(posed));
  if (!(std::abs(det) >= 1e-30) || (det < 0.0) != (glm::determinant(glm::dmat3(rest)) < 0.0)) return rest;
  return posed;
}

std::vector<glm::dmat4> rigidObjectTransforms(const Scene& scene, double time) {
  std::vector<glm::dmat4> out(scene.rigidObjects.size());
  // Global matrices per (clip, clip time): instances that play in phase share them.
  std::map<std::pair<int32_t, double>, std::vector<glm::dmat4>> globals;
  for (size_t i = 0; i < scene.rigidObjects.size(); ++i) {
    const RigidObject& ro = scene.rigidObjects[i];
    const bool animated = ro.clip >= 0 && size_t(ro.clip) < scene.animations.size();
    const int32_t clip = animated ? ro.clip : -1;
    const double t = animated ? clipTime(scene.animations[size_t(clip)], time + ro.timeOffset, true) : 0.0;
    auto it = globals.find({clip, t});
    if (it == globals.end()) {
      Pose pose = restPose(scene.nodes);
      if (animated) sampleClip(scene.animations[size_t(clip)], t, false, pose);
      it = globals.emplace(std::pair{clip, t}, globalMatrices(scene.nodes, pose)).first;
    }
    out[i] = ro.placement * it->second[size_t(ro.node)];
  }
  return out;
}

MorphedVertex morphVertex(const Mesh& mesh, uint32_t v, std::span<const double> weights) {
  const gpu::Vertex& base = mesh.vertices[v];
  MorphedVertex out{glm::dvec3(base.px, base.py, base.pz), glm::dvec3(octDecode(base.normal)), glm::dvec3(0.0)};
  const bool tangent = !mesh.tangents.empty() && mesh.tangents[v].w != 0.0f;
  if (tangent) out.tangent = glm::dvec3(glm::vec3(mesh.tangents[v]));
  glm::dvec3 dn(0.0), dt(0.0);
  for (size_t t = 0; t < mesh.morphTargetCount && t < weights.size(); ++t) {
    if (weights[t] == 0.0) continue;
    const gpu::MorphDelta& d = mesh.morphDeltas[t * mesh.vertices.size() + v];
    out.position += weights[t] * glm::dvec3(d.px, d.py, d.pz);
    dn += weights[t] * glm::dvec3(d.nx, d.ny, d.nz);
    dt += weights[t] * glm::dvec3(d.tx, d.ty, d.tz);
  }
  const glm::dvec3 n = out.normal + dn;
  if (glm::dot(n, n) > 0.0) out.normal = glm::normalize(n);
  const glm::dvec3 tt = out.tangent + dt;
  if (tangent && glm::dot(tt, tt) > 0.0) out.tangent = glm::normalize(tt);
  return out;
}

}  // namespace visbuf
