// GPU structs, defined once for C++ and GLSL (std430 / std140-compatible layouts: only vec4, mat4,
// uint, float members; no vec3 or bool). Sizes are pinned by static_asserts in engine/gpu/types.cpp.
#ifndef VISBUF_TYPES_H
#define VISBUF_TYPES_H

#include "config.h"

#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
namespace visbuf::gpu {
using uint = uint32_t;
using vec4 = glm::vec4;
using mat4 = glm::mat4;
#endif

// One vertex of the unified pool: 32 bytes.
struct Vertex {
  float px, py, pz;  // object-space position
  uint normal;       // octahedral-encoded unit normal, 2 x snorm16 (x in low half)
  float u, v;        // TEXCOORD_0
  uint color;        // RGBA8, R in the low byte
  uint pad;
};

// Optional per-vertex attributes beyond Vertex (16 bytes), only for meshes that have them: tangent and TEXCOORD_1.
struct VertexExtra {
  uint tangent;    // octahedral-encoded unit tangent (xyz); 0 with tangentW 0: none
  float tangentW;  // bitangent sign (+-1), 0: the mesh has no tangents (derived per pixel)
  float u1, v1;    // TEXCOORD_1 (0 when the mesh has none)
};

// One LOD level: a range of the unified index pool. 16 bytes.
struct LodData {
  uint firstIndex;  // into the unified index buffer
  uint indexCount;  // 3 per triangle
  float error;      // object-space simplification error (units of the mesh), 0 for the full mesh
  // Its first ClusterData (one per CLUSTER_TRIANGLES triangles), CLUSTER_NONE: drawn whole (a level of at most
  // CLUSTER_TRIANGLES triangles, a skinned instance's slot)
  uint firstCluster;
};

// A cluster: CLUSTER_TRIANGLES consecutive triangles of a LOD level (the last one of a level may have fewer),
// object space (meshopt_computeClusterBounds). 48 bytes.
struct ClusterData {
  vec4 sphere;  // xyz centre, w radius: contains the cluster's triangles
  vec4 cone;    // xyz unit axis, w cutoff: seen from a point p with dot(normalize(apex - p), axis) >= cutoff, every
                // triangle faces away (cutoff 1: never)
  vec4 apex;    // xyz the cone's apex, w unused
};

// A mesh of the pool. 48 + 16 * MAX_LODS bytes.
struct MeshData {
  vec4 boundsSphere;  // object space: xyz centre, w radius (contains every vertex of every LOD)
  uint vertexOffset;  // added to every index (vertexOffset of the draw)
  uint vertexCount;
  uint lodCount;      // >= 1; lods[0] is the full mesh
  uint extraOffset;   // first VertexExtra of the mesh (indexed by mesh-local vertex), EXTRA_NONE without
  // A skinned instance's slot: buffer device addresses (low, high 32 bits; 0, 0 for every other mesh) of its
  // SkinnedVertex[vertexCount] and its skinned tangents (uint[vertexCount], octahedral; 0, 0 when the mesh has
  // no tangents). Indexed by mesh-local vertex; uv, colour and the tangent's w stay the rest vertex's.
  uint skinnedVertexLow, skinnedVertexHigh;
  uint skinnedTangentLow, skinnedTangentHigh;
  LodData lods[MAX_LODS];
};

// One vertex's morph target delta (36 bytes, float-only so std430 packs it with a stride of 36): position,
// normal and tangent (xyz) offsets added with the target's weight before skinning (glTF: morph, then skin).
// Stored target-major per mesh: deltas[firstMorphDelta + target * vertexCount + vertex].
struct MorphDelta {
  float px, py, pz;
  float nx, ny, nz;
  float tx, ty, tz;
};

// What skinning changes in a vertex (16 bytes): the skinned position and normal of one instance's vertex.
struct SkinnedVertex {
  float px, py, pz;  // skin-space position
  uint normal;       // octahedral-encoded unit normal, as Vertex.normal
};

// One object instance: 64 bytes. The 3x4 affine transform maps object space to world space,
// world relative to the scene anchor (see Scene::anchor); stored as rows.
struct ObjectData {
  vec4 row0;
  vec4 row1;
  vec4 row2;
  uint meshIndex;
  uint materialIndex;
  float maxScale;  // largest singular value bound of the 3x3 part, scales the bounding radius and LOD error
  uint flags;      // OBJECT_FLAG_*
};
#define OBJECT_FLAG_FLIP_WINDING 1u  // negative determinant: front faces are clockwise
#define OBJECT_FLAG_HIDDEN 2u        // neither tested nor drawn: hidden (Renderer::setVisible) or a free slot
#define OBJECT_DRAW_LIST_SHIFT 4u     // bits 4..7: the object's draw list (drawListOf at upload), 15: none (BLEND)

// The draw list of an object (config.h DRAW_LIST_*) from its flags and its material's flags; DRAW_LIST_NONE for
// BLEND materials. The cull pass and the CPU (list capacities, forward path) route with this one function.
#ifdef __cplusplus
inline
#endif
uint drawListOf(uint objectFlags, uint materialFlags) {
  if ((materialFlags & MATERIAL_FLAG_BLEND) != 0u) return DRAW_LIST_NONE;
  uint base = (materialFlags & MATERIAL_FLAG_MASK) != 0u ? DRAW_LIST_MASKED : DRAW_LIST_OPAQUE;
  if ((materialFlags & MATERIAL_FLAG_DOUBLE_SIDED) != 0u) return base + 2u;
  return (objectFlags & OBJECT_FLAG_FLIP_WINDING) != 0u ? base + 1u : base;
}

// The draw list stored in an object's flags (the cull pass reads it without fetching the material).
#ifdef __cplusplus
inline
#endif
uint objectDrawList(uint objectFlags) {
  uint l = (objectFlags >> OBJECT_DRAW_LIST_SHIFT) & 15u;
  return l == 15u ? DRAW_LIST_NONE : l;
}

// One texture slot of a material (48 bytes). image: TEXTURE_NONE, or (size class << 16) | layer of the baked
// image (scene/texture.h); samplerBits: TEXTURE_SAMPLER_* bits; uv' = mat3x2(transform01.xy, transform01.zw,
// transform2.xy) * vec3(uv, 1) (KHR_texture_transform, identity without it).
struct TextureSlotData {
  uint image;
  uint samplerBits;
  float scale;  // the two normal slots: xy scale of the tangent-space normal; 0 elsewhere
  uint pad1;
  vec4 transform01;
  vec4 transform2;
};

// Material (448 bytes): glTF metallic-roughness factors, KHR_materials_clearcoat's and its eight texture slots
// (TEXTURE_SLOT_*).
struct MaterialData {
  vec4 baseColor;  // linear RGBA factor
  vec4 emissive;   // rgb: emissive factor x emissive strength; w: normal texture scale
  vec4 params;     // x: metallic, y: roughness, z: occlusion strength, w: alpha cutoff (MASK)
  uint flags;      // MATERIAL_FLAG_*
  uint slotCount;  // 1 + the last texture slot holding a texture (0: untextured); bounds the shaders' slot loop
  float clearcoat;           // coat weight factor [0,1] (0: no coat)
  float clearcoatRoughness;  // coat roughness factor [0,1]
  TextureSlotData textures[TEXTURE_SLOTS];
};

// The indirect draw written by the cull pass: VkDrawIndexedIndirectCommand plus nothing else,
// so the same buffer is the indirect argument buffer (stride 20 bytes).
struct DrawCommand {
  uint indexCount;
  uint instanceCount;
  uint firstIndex;
  int vertexOffset;
  uint firstInstance;  // object ID
};

// Per-frame constants (uniform buffer, std140 compatible). All positions are camera-relative:
// the CPU computes (anchor - camera) in double and hands the rounded offset in cameraOffset.
struct FrameData {
  mat4 viewProj;        // rotation-only view (camera at origin) x reverse-Z infinite projection
  mat4 view;            // rotation-only view: camera-relative world -> view space (looking down -z)
  vec4 cameraOffset;    // xyz: scene anchor minus camera position (double -> float), w unused
  vec4 frustum[5];      // camera-relative planes (left, right, bottom, top, near): dot(n,p)+w >= 0 inside
  vec4 lightDir;        // xyz: unit direction towards the light (world), w: intensity
  vec4 viewport;        // x: width, y: height, z: 1/width, w: 1/height
  float lodScale;       // perspective: pixels per world unit at distance 1: height / (2 tan(fovY/2)); ortho: per unit
  float lodErrorPixels; // LOD threshold in pixels; <= 0 disables LOD (always level 0)
  float nearPlane;
  uint objectCount;
  uint drawCapacity;
  uint cullMode;        // CULL_NONE / CULL_FRUSTUM
  uint triangleBits;    // ID split: low bits = triangle index within the draw's LOD
  uint wideIds;         // 1: visibility target is rg32ui (x: slot+1, y: triangle); 0: r32ui packed
  float projX;          // proj[0][0]: ndc.x = projX * x / -z (orthographic: projX * x)
  float projY;          // proj[1][1] (negative: Vulkan y down): ndc.y = projY * y / -z (orthographic: projY * y)
  uint pyramidLevels;   // valid levels of the depth pyramid (0 when occlusion is off)
  uint objectSplit;     // objects [0, objectSplit) are in SCENE_BINDING_OBJECTS, the rest in SCENE_BINDING_OBJECTS_HIGH
  uint vertexWindowShift;  // vertex i is in window i >> shift (SCENE_BINDING_VERTICES, SCENE_BINDING_VERTICES_1..3)
  uint pointLightCount;    // PointLightData records in the lights binding (0: none bound, none read)
  uint lightTilesX;        // tiles per row of the light tile lists when this frame built them; 0: every light
  uint msaaSamples;        // raster samples per pixel of the visibility/forward targets: 1 (no MSAA), 2, 4
  // Software micro-raster (sw_raster_pass): 0 off; else the cull pass routes a draw of a list whose drawLists.w is
  // set to it when the object's screen box is at most swMaxPixels per side, it lies wholly beyond the near plane
  // and its LOD has at most swMaxTriangles triangles (so that slot and triangle fit the 32-bit payload).
  uint swRaster;
  float swMaxPixels;
  uint swMaxTriangles;
  uint swTriangleBits;     // payload = (slot << swTriangleBits) | triangle (wide IDs); narrow: the encoded ID
  // Covered-pixel shading (covered_pixels.comp, shade.comp COVERED): the device address of the covered-pixel buffer
  // (COVERED_PIXELS_HEADER uints: the dispatch's x, y, z and the pixel count; then one (x | y << 16) per pixel) and
  // the shading tiles per row. 0: the shading pass dispatches over every pixel.
  uint coveredPixelsLow;
  uint coveredPixelsHigh;
  uint coveredTilesX;
  uint clusterCull;        // 1: the cull pass expands hardware-raster objects into clusters (CULL_CLUSTERS)
  uint earlyClusterOcclusion;  // 1: the early cluster dispatch defers what the previous frame's pyramid hides
  uint framePad0;
  uint framePad1;
  // The micro-raster's bound on an object's (or cluster's) screen box area per triangle, in pixels (a lane loops over
  // a triangle's box serially, so large triangles belong to the hardware raster): FrameOptions::swRasterArea.
  float swMaxAreaPerTriangle;
  // The projection (render/frame_math.h): x = proj[2][2], y = proj[3][2] (reverse-Z depth of the view distance
  // d = -z_view: perspective y / d - x, x = 0 for an infinite far plane; orthographic y - x d); z: 1 orthographic
  // (w_clip = 1, ndc.xy = (projX x, projY y), every view ray parallel to the view direction), 0 perspective; w: the
  // far plane's view distance, 0 where it is infinite. common.glsl's depthOfDistance / viewPositionAt read it.
  vec4 projection;
  vec4 farPlane;        // camera-relative far plane like frustum[] (0, 0, 0, 1 where it is infinite: never culls)
};

// A KHR_lights_punctual light (64 bytes): position relative to the scene anchor (like object translations;
// + cameraOffset gives camera-relative), range (<= 0: infinite), linear RGB colour, intensity (candela; lux for
// a directional light); spot and directional lights: the unit direction the light shines along (world, w 0);
// spot lights: the cone attenuation clamp(cd * angleScale + angleOffset, 0, 1)^2 (engine/scene/light.h).
struct PointLightData {
  vec4 positionRange;
  vec4 colorIntensity;
  vec4 direction;
  float angleScale;
  float angleOffset;
  uint type;  // LIGHT_POINT / LIGHT_SPOT / LIGHT_DIRECTIONAL
  uint pad;
};

// One animated instance of the skinning pass (64 bytes), written by the CPU every pose.
struct SkinInstance {
  uint sourceVertex;  // first rest vertex (pool index)
  uint skinVertex;    // first SkinVertex
  uint vertexCount;
  uint sourceExtra;   // first VertexExtra of the rest mesh (its tangents), EXTRA_NONE without
  uint firstJoint;    // first joint matrix of this instance
  uint meshSlot;      // the instance's MeshData
  uint sourceMesh;    // the rest-pose mesh's MeshData (its LOD errors)
  float lodScale;     // largest joint scale of the pose: multiplies the LOD errors
  vec4 bounds;        // skin space: xyz centre, w radius, contains every skinned vertex of the pose
  // Morph targets (morphTargets 0: none): deltas MorphDelta[firstMorphDelta + t * vertexCount + v]; target t's
  // weight is component t % 4 of joint row morphWeightRow + t / 4 (the rows after the instance's joint rows).
  uint firstMorphDelta;
  uint morphTargets;
  uint morphWeightRow;
  uint morphPad;
};

// Material classification: one record per material (32 bytes; the material tiles buffer, config.h CLASSIFY_HEADER).
// The first three words are the VkDispatchIndirectCommand of the material's shading dispatch: one workgroup per
// listed tile, in rows of CLASSIFY_DISPATCH_WIDTH (written by the scan).
struct MaterialTiles {
  uint groupsX;  // min(tiles, CLASSIFY_DISPATCH_WIDTH)
  uint groupsY;  // ceil(tiles / CLASSIFY_DISPATCH_WIDTH)
  uint groupsZ;  // 1
  uint pixels;   // its pixels on screen
  uint first;    // its first entry in the tile list (exclusive prefix sum of `tiles`)
  uint cursor;   // entries written so far by the scatter
  uint tiles;    // tiles holding at least one of its pixels
  uint pad0;
};

// Push constants of the cull, visibility and depth pyramid passes (16 bytes).
struct PassConstants {
  uint phase;     // CULL_PHASE_EARLY / CULL_PHASE_LATE
  uint drawBase;  // slot of this phase's first draw in the draw buffer (late draws follow the early ones)
  uint material;  // classified shading: the material of this dispatch; classification's scan: the material count;
                  // skinning: SKIN_MODE_* flags
  uint variant;   // cull: which dispatch of a phase (config.h CULL_REFINE ...); skin bounds: the step (SKIN_BOUNDS_*)
};

// Push constants of one depth pyramid dispatch (32 bytes): the valid size of its source level (ceil(size / 2^k)),
// whether it copies the source into level 0 first (the dispatch that reads the depth image), and how many levels it
// reduces (at most PYRAMID_REDUCTIONS).
struct PyramidConstants {
  uint srcWidth, srcHeight;
  uint copySource;
  uint reductions;
  // The first dispatch of a frame whose micro-raster was not merged (FramePlan::swResolved): each source texel is the
  // nearer (the maximum, reverse-Z) of the depth and the micro-raster's depth (its texel view, srcWidth per row).
  uint swResolve;
  uint pad[3];
};

#ifdef __cplusplus
}  // namespace visbuf::gpu
#endif

#endif
