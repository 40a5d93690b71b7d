// Optional pack sections for skeletal animation (docs/pack-format.md, "Animation sections"): the node
// hierarchy, skins, per-vertex skin data of skinned meshes, which objects are skinned, animated morph targets,
// animation clips, and which objects node animation moves rigidly.
// Same rules as pack_format.h (plain little-endian records copied with memcpy, sizes pinned below). A
// section that is absent means "none"; a static scene has none of them, and a reader that does not know
// them skips them (it then draws the rest pose). All "first*" ranges of one kind are disjoint and, summed
// over their records, cover at most their target section.
#pragma once

#include <cstddef>
#include <cstdint>

#include "visbuf/asset/pack_format.h"
#include "visbuf/scene/skin_vertex.h"

namespace visbuf::pack {

inline constexpr uint32_t kNodeHasMatrix = 1u;  // NodeRecord::flags

// Section "nodes": one record per Scene::nodes entry (glTF node order; joints and channels index it).
struct NodeRecord {
  StringRef name;
  int32_t parent;         // node index or -1; the hierarchy has no cycles
  uint32_t flags;         // kNodeHasMatrix: `matrix` is the local transform (never animated), TRS unused
  double translation[3];  // finite
  double rotation[4];     // x, y, z, w; unit length
  double scale[3];        // finite
  double matrix[16];      // column-major, finite (identity when not kNodeHasMatrix)
};
static_assert(sizeof(NodeRecord) == 224 && offsetof(NodeRecord, translation) == 16 &&
              offsetof(NodeRecord, matrix) == 96);

// Section "skins": one record per Scene::skins entry; its joints are skinJoints[firstJoint, + jointCount).
struct SkinRecord {
  StringRef name;
  uint64_t firstJoint;  // into "skinJoints"
  uint32_t jointCount;  // 1..65536
  int32_t skeleton;     // node index or -1
};
static_assert(sizeof(SkinRecord) == 24);

// Section "skinJoints": one record per joint of every skin.
struct SkinJointRecord {
  uint32_t node;           // < node count
  uint32_t reserved;       // 0
  double inverseBind[16];  // column-major, finite, affine (last row 0 0 0 1)
};
static_assert(sizeof(SkinJointRecord) == 136 && offsetof(SkinJointRecord, inverseBind) == 8);

// Section "skinnedMeshes": meshes with per-vertex skin data, one SkinVertex per vertex of the mesh (parallel to
// its vertices), stored encoded in "skinVertices" bytes [firstByte, firstByte + byteCount). At most one record
// per mesh.
struct SkinnedMeshRecord {
  uint32_t mesh;       // < mesh count
  uint32_t reserved;   // 0
  uint64_t firstByte;  // into "skinVertices"
  uint64_t byteCount;  // > 0; the mesh's vertexCount records through the vertex codec (pack_geometry.h)
};
static_assert(sizeof(SkinnedMeshRecord) == 24);

// Section "skinVertices": bytes (elementSize 1): per skinned mesh, its SkinVertex records (scene/skin_vertex.h:
// joints u16 x 8, weights f32 x 8, 48 bytes) through meshoptimizer's vertex codec (version 0), like "vertices".
static_assert(sizeof(SkinVertex) == 48 && offsetof(SkinVertex, weights) == 16);

// Section "skinnedObjects": Scene::skinnedObjects, at most one record per object.
struct SkinnedObjectRecord {
  uint32_t object;  // < object count; its mesh has a "skinnedMeshes" record
  uint32_t skin;    // < skin count; covers every joint index of the mesh's skin vertices
};
static_assert(sizeof(SkinnedObjectRecord) == 8);

// Section "morphMeshes": meshes with animated morph targets (Mesh::morphTargetCount > 0), at most one record
// per mesh: deltas morphDeltas[firstDelta, + targetCount x the mesh's vertexCount), target-major
// (delta of target t, vertex v at firstDelta + t * vertexCount + v), default weights
// morphWeights[firstWeight, + targetCount).
struct MorphMeshRecord {
  uint32_t mesh;         // < mesh count
  uint32_t targetCount;  // 1..65536
  uint64_t firstDelta;   // into "morphDeltas"
  uint64_t firstWeight;  // into "morphWeights"
};
static_assert(sizeof(MorphMeshRecord) == 24);

// Section "morphDeltas": gpu::MorphDelta records (shared/types.h): position, normal, tangent xyz deltas, f32
// x 9, finite.
static_assert(sizeof(gpu::MorphDelta) == 36 && offsetof(gpu::MorphDelta, nx) == 12 &&
              offsetof(gpu::MorphDelta, tx) == 24);

// Section "morphWeights": f32 default weights, finite.

// Section "morphObjects": the morph node of skinned objects whose mesh has morph targets
// (SkinnedObject::morphNode), at most one record per skinned object.
struct MorphObjectRecord {
  uint32_t skinnedObject;  // < "skinnedObjects" count; its object's mesh has a "morphMeshes" record
  uint32_t node;           // < node count: whose animated weights drive the targets
};
static_assert(sizeof(MorphObjectRecord) == 8);

// Section "animations": one record per clip; samplers animSamplers[firstSampler, + samplerCount), channels
// animChannels[firstChannel, + channelCount).
struct AnimationRecord {
  StringRef name;
  double duration;  // seconds: the last key time over the clip's samplers
  uint32_t firstSampler;
  uint32_t samplerCount;
  uint32_t firstChannel;
  uint32_t channelCount;
};
static_assert(sizeof(AnimationRecord) == 32);

// Section "animSamplers": keys animTimes[firstTime, + keyCount), values animValues[firstValue, + keyCount x
// components x (3 for cubic spline, else 1)).
struct AnimSamplerRecord {
  uint32_t interpolation;  // Interpolation: 0 linear, 1 step, 2 cubic spline
  uint32_t components;     // 3 translation/scale, 4 rotation, morph target count for weights (1..65536)
  uint64_t firstTime;      // into "animTimes"
  uint64_t keyCount;       // >= 1
  uint64_t firstValue;     // into "animValues"
};
static_assert(sizeof(AnimSamplerRecord) == 32);

// Section "animChannels".
struct AnimChannelRecord {
  uint32_t sampler;   // relative to the clip's firstSampler, < samplerCount
  uint32_t node;      // target node, < node count, without kNodeHasMatrix
  uint32_t path;      // AnimationPath: 0 translation, 1 rotation, 2 scale, 3 weights
  uint32_t reserved;  // 0
};
static_assert(sizeof(AnimChannelRecord) == 16);

// Sections "animTimes" and "animValues": f32 (times in seconds, strictly increasing per sampler; values
// finite).

// Section "rigidObjects" (version 6): Scene::rigidObjects, objects placed by an animated node's global matrix,
// at most one record per object, none for a skinned object.
struct RigidObjectRecord {
  uint32_t object;       // < object count
  int32_t node;          // 0 <= node < node count
  int32_t clip;          // -1 (rest pose) or < animation count
  uint32_t reserved;     // 0
  double timeOffset;     // seconds, finite
  double placement[16];  // column-major, finite, affine (last row 0 0 0 1)
};
static_assert(sizeof(RigidObjectRecord) == 152 && offsetof(RigidObjectRecord, timeOffset) == 16 &&
              offsetof(RigidObjectRecord, placement) == 24);

// Section "cameras" (pack_cameras.cpp; absent when the scene has no cameras and a plain default camera): the
// scene's cameras (Scene::cameras, in order), then at most one record with flags bit 0 set: the default camera's
// projection (its pose and fovY / near stay in the "scene" record, which a reader of a pack without this section
// takes as an infinite reverse-Z perspective). Every value is checked with validateCamera() on reading.
struct CameraRecord {
  StringRef name;
  uint32_t projection;  // Projection: 0 perspective, 1 orthographic
  uint32_t flags;       // bit 0: the default camera's projection (name empty); other bits 0
  double position[3], target[3], up[3];
  double fovY, nearPlane, farPlane;  // farPlane may be +infinity (perspective)
  double aspectRatio, xmag, ymag;
};
static_assert(sizeof(CameraRecord) == 136 && offsetof(CameraRecord, position) == 16);

inline constexpr const char* kNodesSection = "nodes";
inline constexpr const char* kSkinsSection = "skins";
inline constexpr const char* kSkinJointsSection = "skinJoints";
inline constexpr const char* kSkinnedMeshesSection = "skinnedMeshes";
inline constexpr const char* kSkinVerticesSection = "skinVertices";
inline constexpr const char* kSkinnedObjectsSection = "skinnedObjects";
inline constexpr const char* kMorphMeshesSection = "morphMeshes";
inline constexpr const char* kMorphDeltasSection = "morphDeltas";
inline constexpr const char* kMorphWeightsSection = "morphWeights";
inline constexpr const char* kMorphObjectsSection = "morphObjects";
inline constexpr const char* kAnimationsSection = "animations";
inline constexpr const char* kAnimSamplersSection = "animSamplers";
inline constexpr const char* kAnimChannelsSection = "animChannels";
inline constexpr const char* kAnimTimesSection = "animTimes";
inline constexpr const char* kAnimValuesSection = "animValues";
inline constexpr const char* kRigidObjectsSection = "rigidObjects";
inline constexpr const char* kCamerasSection = "cameras";

}  // namespace visbuf::pack
