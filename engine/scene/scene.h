// CPU truth of a scene: optimised meshes with LOD chains, materials, object instances, camera.
// Positions are double on the CPU; the GPU mirror stores them relative to `anchor` in float.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/core/result.h"
#include "visbuf/scene/animation.h"
#include "visbuf/scene/light.h"
#include "visbuf/scene/mesh.h"
#include "visbuf/scene/texture.h"
#include "visbuf/scene/skin_vertex.h"
#include "visbuf/shared/types.h"

namespace visbuf {

struct Lod {
  uint32_t firstIndex = 0;  // relative to Mesh::indices
  uint32_t indexCount = 0;
  float error = 0.0f;       // object-space simplification error vs the full mesh (mesh units)
};

// A mesh ready for the geometry pool: deduplicated, cache/fetch-optimised, with its LOD chain.
struct Mesh {
  std::string name;
  std::vector<gpu::Vertex> vertices;
  // Optional streams parallel to `vertices` (empty, or one per vertex; see MeshSource), kept out of the
  // 32-byte gpu::Vertex that every pass reads.
  std::vector<glm::vec4> tangents;
  std::vector<glm::vec2> uvs1;
  std::vector<uint32_t> indices;  // every LOD, concatenated; indices are mesh-local
  std::vector<Lod> lods;          // lods[0] = full mesh; error non-decreasing
  std::vector<SkinVertex> skinVertices;  // empty, or parallel to vertices (a skinned mesh)
  // Morph targets (empty: none): morphTargetCount x vertices.size() deltas, target-major
  // (morphDeltas[t * vertices.size() + v]), parallel to `vertices` like the streams above; the LOD levels index
  // the same vertices, so they share them. Only meshes whose node has an animated weights channel keep their
  // targets (every other mesh has its weights baked into `vertices` by the importer); `vertices` is then the
  // base shape (all weights 0) and an animated object of it is a SkinnedObject with morphNode set.
  uint32_t morphTargetCount = 0;
  std::vector<gpu::MorphDelta> morphDeltas;
  std::vector<float> morphWeights;  // default weights (one per target), used where no channel sets the node's
  glm::vec4 boundsSphere{0.0f};   // contains every vertex
  uint32_t triangleCount(size_t lod = 0) const { return lods[lod].indexCount / 3; }
  glm::vec3 position(uint32_t vertex) const {
    const auto& v = vertices[vertex];
    return {v.px, v.py, v.pz};
  }
};

struct MeshBuildOptions {
  uint32_t maxLods = MAX_LODS;     // including the full mesh
  uint32_t minTriangles = 16;      // stop the chain once a level reaches this
  float minReduction = 0.85f;      // a level must keep at most this fraction of the previous one
  // Above fineBelowTriangles each level aims at lodRatio of the previous one's triangles. Below it (the levels
  // distant instances draw) candidates are simplified at targets fineLodRatio apart, by both simplifiers, and
  // measured; the chain takes the subset that draws the fewest triangles for a log-uniform spread of pixel
  // thresholds (so each instance draws a level close to its threshold), within maxLods.
  float lodRatio = 0.5f;
  float fineLodRatio = 0.85f;
  uint32_t fineBelowTriangles = 2048;
};

// Optimises a source mesh and builds its LOD chain with meshoptimizer. Errors on empty or invalid
// input (indices out of range, non-finite positions).
Result<Mesh> buildMesh(const MeshSource& source, const MeshBuildOptions& options = {});

// glTF alpha modes. Values are stored in packs: never renumber.
enum class AlphaMode : uint32_t { Opaque = 0, Mask = 1, Blend = 2 };

struct Material {
  std::string name;
  glm::vec4 baseColor{1.0f};  // linear RGBA, each in [0,1]
  AlphaMode alphaMode = AlphaMode::Opaque;
  float alphaCutoff = 0.5f;   // AlphaMode::Mask: fragments with alpha < cutoff are discarded
  bool doubleSided = false;
  TextureRef baseColorTexture;  // sRGB; multiplies baseColor
  // Metallic-roughness model (glTF 2.0 core); defaults are glTF's.
  float metallic = 1.0f;              // [0,1]
  float roughness = 1.0f;             // [0,1]
  TextureRef metallicRoughnessTexture;  // linear; B: metallic, G: roughness (multiply the factors)
  TextureRef normalTexture;           // linear, tangent space; xy scaled by normalScale
  float normalScale = 1.0f;
  TextureRef occlusionTexture;        // linear; R: occlusion, strength lerps from 1 to it
  float occlusionStrength = 1.0f;     // [0,1]
  glm::vec3 emissive{0.0f};           // linear RGB factor, each in [0,1]
  float emissiveStrength = 1.0f;      // KHR_materials_emissive_strength, >= 0; multiplies emissive
  TextureRef emissiveTexture;         // sRGB; multiplies emissive * emissiveStrength
  // KHR_materials_unlit: the pixel's colour is the base colour (factor x texture x vertex colour) as is; every
  // other property (lights, occlusion, emissive, normals, clearcoat) is ignored. Alpha modes still apply.
  bool unlit = false;
  // KHR_materials_clearcoat: a dielectric (ior 1.5, f0 0.04) GGX layer over the base with its own roughness and
  // normal. clearcoat 0 (the default): no layer. The extension's defaults; factors in [0,1].
  float clearcoat = 0.0f;                // layer weight; times clearcoatTexture R
  float clearcoatRoughness = 0.0f;       // perceptual; times clearcoatRoughnessTexture G
  TextureRef clearcoatTexture;           // linear; R: weight
  TextureRef clearcoatRoughnessTexture;  // linear; G: roughness
  TextureRef clearcoatNormalTexture;     // linear, tangent space; none: the coat uses the geometric normal
  float clearcoatNormalScale = 1.0f;     // xy scale of clearcoatNormalTexture
  // KHR_materials_pbrSpecularGlossiness with a texture, until bakeTextures converts its texels (spec_gloss.h): the
  // diffuse texture is in baseColorTexture (sRGB), the specular-glossiness one in metallicRoughnessTexture (RGB
  // sRGB, A linear), and these are the extension's factors; baseColor / metallic / roughness meanwhile hold the
  // factors' own conversion (what a render without baked textures shows). Not stored in packs (baked away).
  struct SpecGlossSource {
    glm::vec4 diffuse{1.0f};
    glm::vec3 specular{1.0f};
    float glossiness = 1.0f;
  };
  std::optional<SpecGlossSource> specGloss;
};

// A material's eight texture slots in a fixed order (packs store them in this order): base colour,
// metallic-roughness, normal, occlusion, emissive, clearcoat, clearcoat roughness, clearcoat normal
// (config.h TEXTURE_SLOT_*).
inline constexpr size_t kTextureSlotCount = 8;
std::array<const TextureRef*, kTextureSlotCount> textureSlots(const Material& m);
std::array<TextureRef*, kTextureSlotCount> textureSlots(Material& m);
// Colour space of a slot's texels: Srgb for base colour and emissive, Linear for the data textures.
ColorSpace textureSlotColorSpace(size_t slot);
// MATERIAL_FEATURE_* bits (config.h) a material's shading needs: unlit, a clearcoat layer (clearcoat > 0).
uint32_t materialFeatures(const Material& m);

struct Object {
  glm::dmat4 transform{1.0};  // object -> world (affine)
  uint32_t mesh = 0;
  uint32_t material = 0;
};

// How a camera projects (glTF camera.type). Values are stored in packs: never renumber.
enum class Projection : uint32_t { Perspective = 0, Orthographic = 1 };

// A camera: a rigid pose and a projection (render/frame_math.h builds the matrices the renderer consumes).
// The pose is held in look-at form: the camera sits at `position`, looks towards `target` and `up` picks the roll
// (any vector not parallel to the view direction). setCameraPose() / setCameraView() set it from a camera -> world
// or world -> view matrix instead (glTF cameras: the node's world transform, scale removed).
// The depth buffer is reverse-Z (1 at the near plane, 0 at the far plane or at infinity) for both projections.
// Aspect: the projection's authored window (perspective: tan(fovY/2) * aspectRatio by tan(fovY/2); orthographic:
// xmag by ymag) is fitted inside the viewport without distortion: the axis where the viewport is relatively wider
// sees more than authored, the other exactly what was authored. aspectRatio 0 (glTF: absent) is the viewport's, so
// fovY is then always the vertical field of view.
struct Camera {
  glm::dvec3 position{0.0, 0.0, 5.0};
  glm::dvec3 target{0.0};
  glm::dvec3 up{0.0, 1.0, 0.0};
  Projection projection = Projection::Perspective;
  double fovY = glm::radians(60.0);  // perspective: vertical field of view, radians, in (0, pi)
  double nearPlane = 0.1;            // distance along the view direction: perspective > 0, orthographic >= 0
  // Perspective: > nearPlane, or +infinity (an infinite far plane, the default); orthographic: finite, > nearPlane.
  double farPlane = INFINITY;
  double aspectRatio = 0.0;          // perspective: authored width / height (> 0), or 0: the viewport's
  double xmag = 1.0, ymag = 1.0;     // orthographic: half width and half height of the view volume (world units)
};

// Clear errors (InvalidArgument, naming the field) for a camera the renderer cannot draw: non-finite values, position
// == target, an up vector parallel to the view direction, fovY outside (0, pi), nearPlane <= 0 (perspective) or < 0
// (orthographic), farPlane <= nearPlane, an infinite orthographic farPlane, aspectRatio < 0, xmag or ymag <= 0.
Status validateCamera(const Camera& camera);
// Sets the pose from a camera -> world matrix (affine; its scale and shear are removed: the columns are
// orthonormalised, -Z the view direction, +Y up). Error where the linear part is singular or non-finite.
Status setCameraPose(Camera& camera, const glm::dmat4& cameraToWorld);
// The same from a world -> view matrix (its inverse).
Status setCameraView(Camera& camera, const glm::dmat4& worldToView);

// A camera a file carries (glTF: a node with a camera), for `render --camera gltf:N` and hosts.
struct NamedCamera {
  std::string name;  // the glTF camera's name, else its node's (may be empty)
  Camera camera;
  bool operator==(const NamedCamera& o) const;
};

// An object drawn with skinning: its mesh's vertices are skinned by `skin` each frame (the object's
// transform is not applied to skinned vertices; glTF ignores the skinned mesh node's transform). Its
// culling bound at a pose is skinnedBoundsSphere() (animation.h), not the mesh's rest-pose boundsSphere.
struct SkinnedObject {
  uint32_t object = 0;  // into Scene::objects; its mesh has skinVertices
  uint32_t skin = 0;    // into Scene::skins; covers every joint index of the mesh's skinVertices
  // Playback (not stored in packs: every instance of a pack plays clip 0 from time 0 in place).
  int32_t clip = 0;            // Scene::animations index played (looping); no such clip: the rest pose
  double timeOffset = 0.0;     // seconds added to the frame's animation time: each instance its own phase
  glm::dmat4 placement{1.0};   // world placement of the skinned result (identity for a file's own instances)
  // Morph targets: the node whose animated weights (Pose::weights) drive the mesh's morph targets (the mesh's
  // default morphWeights where no channel sets them), -1 for a mesh without targets. A morph-only mesh (no
  // glTF skin) is skinned with a one-joint skin whose joint is this node (identity inverse bind): its global
  // matrix is exactly the node transform glTF applies to an unskinned mesh.
  int32_t morphNode = -1;
  bool operator==(const SkinnedObject&) const = default;
};

// An unskinned object moved by node animation (glTF: a translation / rotation / scale channel on its mesh node or
// on an ancestor of it, as CesiumMilkTruck's wheels). It is a plain object (no skin, no per-vertex work): its
// object -> world transform at animation time t is rigidObjectTransform(scene, *this, t). Its Object::transform
// holds rigidObjectStartTransform(): that transform at time 0 (the clip's pose at clip time timeOffset for the
// nodes the clip animates, the rest TRS for the others), so drawing the objects as they are shows the time-0
// pose. The object's mesh winding (and mirrored variant) was chosen for the rest pose: a pose that is singular
// or flips the handedness cannot be drawn with it.
struct RigidObject {
  uint32_t object = 0;        // into Scene::objects; not a skinned object
  int32_t node = 0;           // into Scene::nodes: the mesh node, whose global matrix places the object
  int32_t clip = 0;           // Scene::animations index played (looping); -1: the rest pose
  double timeOffset = 0.0;    // seconds added to the animation time: each instance its own phase
  glm::dmat4 placement{1.0};  // world placement of the node's global matrix (identity for a file's own objects)
  bool operator==(const RigidObject&) const = default;
};

struct Scene {
  std::string name;
  std::vector<Mesh> meshes;
  std::vector<Material> materials;
  std::vector<Object> objects;
  std::vector<Texture> textures;            // baked images, referenced by TextureRef::baked
  std::vector<TextureClass> textureClasses; // their pixels (texture.h)
  // Animation (all empty for a static scene): the node hierarchy (joints and channels index it), skins,
  // clips, and which objects are skinned (at most one entry per object).
  std::vector<SceneNode> nodes;
  std::vector<Skin> skins;
  std::vector<AnimationClip> animations;
  std::vector<SkinnedObject> skinnedObjects;
  std::vector<RigidObject> rigidObjects;  // at most one entry per object, none for a skinned object
  glm::dvec3 anchor{0.0};  // GPU positions are relative to this point
  Camera defaultCamera;
  std::vector<NamedCamera> cameras;  // the file's cameras (glTF: every camera node of the default scene, in node order)
  glm::vec3 lightDirection = glm::normalize(glm::vec3(0.4f, 0.8f, 0.45f));  // towards the light
  // Its illuminance (0: none). 0.85 pi: a white Lambertian surface facing it reflects 0.85 (lighting.glsl).
  float lightIntensity = 2.6703538f;
  std::vector<PointLight> pointLights;  // none: no light culling pass, no light buffers (renderer.cpp)

  uint64_t totalTriangles() const;  // full-detail triangles over all objects
};

// Checks a scene before upload: indices, finite transforms, mesh/material references, and
// validateSceneAnimation().
Status validateScene(const Scene& scene);
// The animation part (scene_animation.cpp): validateNodes / validateSkin / validateClip, skin vertex counts
// and weights, skinned objects' object/skin references, joint indices below the skin's joint count, and rigid
// objects' object / node / clip references (each object once, never a skinned one), finite time offsets and
// finite affine placements.
Status validateSceneAnimation(const Scene& scene);
// The object -> world transform of rigid object `ro` at animation time `time` (double precision):
// ro.placement * global(ro.node) with the node chain posed by clip ro.clip at time + ro.timeOffset (looping;
// restPose + sampleClip + globalMatrices of animation.h; the rest pose when clip is -1). The node's own
// static TRS and those of its ancestors are part of global(node). Precondition: validateSceneAnimation passed.
glm::dmat4 rigidObjectTransform(const Scene& scene, const RigidObject& ro, double time);
// What the importer and makeAnimatedField store in Object::transform for rigid object `ro`: rigidObjectTransform
// at time 0 when it is finite, has |det| >= 1e-30 (validateScene's bound) and the handedness of `rest`; else
// `rest` (the object's transform in the file's rest pose, e.g. for a clip that starts at scale 0).
glm::dmat4 rigidObjectStartTransform(const Scene& scene, const RigidObject& ro, const glm::dmat4& rest);
// rigidObjectTransform of every Scene::rigidObjects entry at `time` (result[i] for rigidObjects[i]); objects that
// share a clip and clip time share one pose evaluation.
std::vector<glm::dmat4> rigidObjectTransforms(const Scene& scene, double time);
// The joint matrices (double precision, skin space) of skinned object `so` at animation time `time` (plus its
// timeOffset, its clip looping; the rest pose without a clip): the pose the skinning pass skins with.
std::vector<glm::dmat4> skinnedObjectJoints(const Scene& scene, const SkinnedObject& so, double time);
// Its morph weights at that time (one per target of its mesh, none without targets): the morph node's
// animated weights where the clip sets them (a channel with fewer values leaves the rest at the default),
// else the mesh's default morphWeights (0 where it has none).
std::vector<double> skinnedObjectMorphWeights(const Scene& scene, const SkinnedObject& so, double time);
// Reference morphing (double precision, glTF): vertex v of `mesh` under `weights` (weights[t] for target t;
// missing ones 0): position p + sum w_t dp_t; normal normalize(n + sum w_t dn_t) (n the stored, decoded normal;
// the base normal where the sum is zero); tangent xyz likewise from Mesh::tangents ((0,0,0) without).
struct MorphedVertex {
  glm::dvec3 position, normal, tangent;
};
MorphedVertex morphVertex(const Mesh& mesh, uint32_t v, std::span<const double> weights);

// World-space centre of an object's bounding sphere (double precision; its mesh index must be valid).
glm::dvec3 objectCentreWorld(const Scene& scene, const Object& object);
// World-space bounding sphere of an object (double precision, conservative: uses the largest
// column norm of the 3x3 part as the scale).
glm::dvec4 objectBoundsWorld(const Scene& scene, const Object& object);
// The same with maxScaleOf(object.transform) already computed (per-object loops need it twice).
glm::dvec4 objectBoundsWorld(const Scene& scene, const Object& object, double maxScale);
double maxScaleOf(const glm::dmat4& m);
// World-space bounding sphere (xyz centre, w radius; double precision) of every object over the whole animation:
// static objects as objectBoundsWorld; rigid objects (rigidObjectTransform) and skinned / morphed objects (their
// vertices skinned on the CPU, skinnedObjectJoints + skinnedObjectMorphWeights) at the rest pose and at sampled times
// of every clip of the scene (each clip's key times and a 30 Hz grid over [0, duration], thinned for large skinned
// meshes), whatever clip or phase the object plays. (0,0,0,0) for a scene without objects. Between samples a pose may
// reach a little further: framing adds a margin.
glm::dvec4 animatedSceneBounds(const Scene& scene);

// The scene's objects in spatial order: sorted along a Morton (Z-order) curve of their bounding spheres' centres,
// quantised to 2^21 cells on the longest side of the centres' box (ties keep the scene's order). order[k] is the
// index of the object that goes k-th: a permutation of [0, objects).
std::vector<uint32_t> spatialObjectOrder(const Scene& scene);
// Puts the objects in that order, renumbering the skinned and rigid objects' references with them; returns the
// order (new index -> old index). The GPU-driven passes read the object records by object ID, so objects that are
// neighbours in space and in ID share cache lines and subgroups: on lavapipe the 1M-kitten field view's frame takes
// 0.90x the time it takes with the generator's random order (docs/benchmarks.md). The image is the same.
std::vector<uint32_t> orderObjectsSpatially(Scene& scene);

// Octahedral encoding of a unit normal into 2 x snorm16 (matches octDecode in shaders/common.glsl).
uint32_t octEncode(glm::vec3 n);
glm::vec3 octDecode(uint32_t packed);

}  // namespace visbuf
