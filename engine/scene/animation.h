// Skeletal animation on the CPU: the node hierarchy, skins, animation clips (glTF 2.0 semantics), pose
// evaluation in double precision, joint matrices for the skinning pass, a double-precision reference
// skinning, and a conservative bounding sphere of a skinned mesh at any pose. Pure CPU, no Vulkan, no glTF
// library: the importer (asset/gltf_import) and the pack reader fill these types.
//
// Conventions (glTF 2.0):
//   - Nodes are indexed as in the source file; joints and animation channels refer to them by that index.
//   - A node's local matrix is T * R * S (or its `matrix` when it has one; such nodes are never animated).
//   - A skinned vertex is  p' = sum_i w_i * J_i * p  with  J_i = global(joints[i]) * inverseBind[i]  (the
//     joint matrix). The transform of the node that holds the skinned mesh is NOT applied (glTF: "only the
//     joint transforms are applied to the skinned mesh"), so p' is in the space of the scene's roots (world).
//   - Times are seconds; rotations are unit quaternions (glm::dquat: w, x, y, z).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "visbuf/core/result.h"
#include "visbuf/scene/skin_vertex.h"

namespace visbuf {

// A node's local transform as translation, rotation, scale.
struct NodeTransform {
  glm::dvec3 translation{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};  // unit length
  glm::dvec3 scale{1.0};
  glm::dmat4 matrix() const;  // T * R * S
  bool operator==(const NodeTransform&) const = default;
};

struct SceneNode {
  std::string name;
  int32_t parent = -1;     // node index, -1 for a root; the hierarchy is a forest (no cycles)
  NodeTransform rest;      // the file's TRS (identity when it has a matrix)
  bool hasMatrix = false;  // the file gave `matrix` instead of TRS: `matrix` is used, never animated
  glm::dmat4 matrix{1.0};  // local matrix when hasMatrix, finite
  bool operator==(const SceneNode&) const = default;
};

struct Skin {
  std::string name;
  std::vector<uint32_t> joints;  // node indices; SkinVertex::joints index this list
  std::vector<glm::dmat4>
      inverseBindMatrices;  // one per joint, finite, affine (identity when the file has none)
  int32_t skeleton = -1;    // node index of the skeleton root (informational), -1: none
  bool operator==(const Skin&) const = default;
};

// Values are stored in enums in packs: never renumber.
enum class AnimationPath : uint32_t { Translation = 0, Rotation = 1, Scale = 2, Weights = 3 };
enum class Interpolation : uint32_t { Linear = 0, Step = 1, CubicSpline = 2 };

// Keyframes of one animated property. `values` holds, per key, `components` floats (LINEAR, STEP) or three
// groups of `components` floats (CUBICSPLINE: in-tangent, value, out-tangent), so
// values.size() == times.size() * components * (CubicSpline ? 3 : 1).
struct AnimationSampler {
  Interpolation interpolation = Interpolation::Linear;
  uint32_t components = 0;    // 3 translation/scale, 4 rotation (x, y, z, w as in glTF), N morph weights
  std::vector<float> times;   // >= 1 key, finite, strictly increasing (seconds)
  std::vector<float> values;  // finite
  bool operator==(const AnimationSampler&) const = default;
};

struct AnimationChannel {
  uint32_t sampler = 0;  // into AnimationClip::samplers
  uint32_t node = 0;     // target node index (a node with hasMatrix == false)
  AnimationPath path = AnimationPath::Translation;
  bool operator==(const AnimationChannel&) const = default;
};

struct AnimationClip {
  std::string name;
  std::vector<AnimationSampler> samplers;
  std::vector<AnimationChannel> channels;
  double duration = 0.0;  // last key time over all samplers (>= 0); the clip plays over [0, duration]
  bool operator==(const AnimationClip&) const = default;
};

// The animated state of every node: local transforms plus morph weights of nodes with a weights channel.
struct Pose {
  std::vector<NodeTransform> locals;         // one per node
  std::vector<std::vector<double>> weights;  // one per node; empty unless a weights channel set it
};

// --- validation (used by the importer and the pack reader; messages name the node / skin / clip) -----------
// Parents exist and the hierarchy has no cycles; matrices and TRS finite, rotations unit length (1e-3).
Status validateNodes(const std::vector<SceneNode>& nodes);
// Joints exist (< nodeCount), one finite affine inverse bind matrix per joint, skeleton -1 or a node,
// at most 65536 joints (SkinVertex stores 16-bit joint indices).
Status validateSkin(const Skin& skin, size_t nodeCount, const std::string& where);
// Sampler shapes (keys, strictly increasing finite times, value counts per interpolation, finite values),
// channel targets (node exists, has no matrix, components fit the path), duration = last key time.
Status validateClip(const AnimationClip& clip, const std::vector<SceneNode>& nodes, const std::string& where);

// --- evaluation ------------------------------------------------------------------------------------------
// The clip time used for `time` seconds: looping wraps into [0, duration) (duration 0: always 0); otherwise
// `time` itself (samplers clamp it to their first / last key).
double clipTime(const AnimationClip& clip, double time, bool loop);

// Evaluates one sampler at `time` (already a clip time) into out[0 .. components). Before the first key the
// first value, after the last key the last value. LINEAR: component-wise lerp, but Rotation uses the glTF
// spherical interpolation (shortest arc of the normalised keys). STEP: the value of the last key <= time.
// CUBICSPLINE: cubic Hermite spline with tangents scaled by the key interval (glTF appendix C).
// Rotations always come out normalised. `out` must hold `components` doubles.
void sampleSampler(const AnimationSampler& sampler, AnimationPath path, double time, std::span<double> out);

// The rest pose (every node's own TRS, no weights).
Pose restPose(const std::vector<SceneNode>& nodes);
// Overwrites in `pose` every property the clip animates with its value at clipTime(clip, time, loop).
// Properties not animated by the clip keep their value (start from restPose() for a plain clip pose).
// Channels whose node is outside `pose` are ignored (validateClip rejects them).
void sampleClip(const AnimationClip& clip, double time, bool loop, Pose& pose);

// Local -> root ("world") matrix of every node: parent global * local, in double precision, with matrix
// nodes using their matrix. Parents may come after their children in the list. Precondition: pose.locals
// has one entry per node and validateNodes(nodes) passed.
std::vector<glm::dmat4> globalMatrices(const std::vector<SceneNode>& nodes, const Pose& pose);

// Joint matrices J_j = global(joints[j]) * inverseBindMatrices[j], in double precision.
std::vector<glm::dmat4> jointMatrices(const Skin& skin, const std::vector<glm::dmat4>& globals);
// The same relative to `origin` (camera-relative rendering): T(-origin) * J_j, computed in double, then
// rounded to float. Skinned positions come out relative to origin, so float keeps full precision far away.
std::vector<glm::mat4> jointMatricesRelative(const Skin& skin, const std::vector<glm::dmat4>& globals,
                                             glm::dvec3 origin);

// --- reference skinning (double precision) -------------------------------------------------------------
// The weighted joint matrix sum_i w_i * J_i of a vertex. Precondition: every joint index with a non-zero
// weight is < joints.size() (slots with weight 0 are skipped).
glm::dmat4 blendedJointMatrix(const SkinVertex& skin, std::span<const glm::dmat4> joints);
// p' = B * p with B = blendedJointMatrix().
glm::dvec3 skinPosition(glm::dvec3 position, const SkinVertex& skin, std::span<const glm::dmat4> joints);
// n' = normalize(cofactor(B3x3) * n * sign(det B)): the inverse-transpose direction, exact under
// non-uniform scale and defined for singular B. A zero result (degenerate B) stays (0, 0, 0).
glm::dvec3 skinNormal(glm::dvec3 normal, const SkinVertex& skin, std::span<const glm::dmat4> joints);
// t' = normalize(B3x3 * t): a tangent is a direction within the surface, so it maps like a position
// difference (its handedness w is unchanged). A zero result (degenerate B) stays (0, 0, 0).
glm::dvec3 skinTangent(glm::dvec3 tangent, const SkinVertex& skin, std::span<const glm::dmat4> joints);

// --- conservative bounds -----------------------------------------------------------------------------------
// Per joint j < jointCount, in mesh (bind) space: a sphere (xyz centre, w radius) containing every vertex
// that joint j influences with a weight > 0; w = -1 for a joint that influences no vertex.
// skin.size() must equal positions.size(); joint indices >= jointCount are ignored.
std::vector<glm::dvec4> jointInfluenceSpheres(std::span<const glm::vec3> positions,
                                              std::span<const SkinVertex> skin, size_t jointCount);
// A sphere (xyz centre, w radius) that contains every skinned vertex p' = sum_i w_i J_i p of the mesh the
// spheres were computed from, for the given joint matrices (jointMatrices() of any pose, or relative ones
// converted to double). Proof in animation.cpp. Returns w = +inf when a joint matrix is not affine (no
// bound possible) and (0,0,0,-1) when no joint influences anything. joints.size() >= spheres.size().
glm::dvec4 skinnedBoundsSphere(std::span<const glm::dvec4> spheres, std::span<const glm::dmat4> joints);

}  // namespace visbuf
