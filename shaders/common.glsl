// Shared declarations of every pass: bindings, the object transform (the one definition of the raster
// math, used by the visibility, shading and forward shaders alike) and normal decode. Lighting: lighting.glsl.
#ifndef VISBUF_COMMON_GLSL
#define VISBUF_COMMON_GLSL
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#include "shared/types.h"
#include "octahedral.glsl"

layout(set = 0, binding = SCENE_BINDING_FRAME) uniform FrameBlock { FrameData frame; };
// 1: object records and vertices are read through their descriptor windows; 0 (a scene that fits one range
// each): directly, with no per-fetch branch. Set per renderer (gpu::createComputePipeline).
layout(constant_id = 0) const uint VB_WINDOWED = 1u;
// 1: object records, vertices and indices are read through uniform texel buffer views (GpuScene::texels; only for
// scenes that need no descriptor windows). On lavapipe a texel is one vector load, while a storage-buffer read is
// a bounds-checked scalar load per lane and word: the cull, micro-raster and shading passes fetch per object,
// triangle or pixel. Set per renderer (gpu::Specialization::texels).
layout(constant_id = 3) const uint VB_TEXELS = 0u;
// 0: no mesh of the scene has VertexExtra records (MeshData.extraOffset is EXTRA_NONE everywhere), resp. the scene
// has no punctual lights: the code that reads them is removed (lavapipe runs a branch's body under a lane mask even
// when no lane takes it). Set per renderer (gpu::Specialization::extras, ::pointLights).
layout(constant_id = 4) const uint VB_EXTRAS = 1u;
layout(constant_id = 5) const uint VB_POINT_LIGHTS = 1u;
// MATERIAL_FEATURE_* bits a pipeline may meet (config.h): the shading code of the others is removed. Set per
// renderer and, for classified shading, per material (gpu::Specialization::materialFeatures).
layout(constant_id = 6) const uint VB_MATERIAL_FEATURES = MATERIAL_FEATURES_ALL;
layout(set = 0, binding = SCENE_BINDING_VERTEX_TEXELS) uniform usamplerBuffer vertexTexels;  // 2 texels per Vertex
layout(set = 0, binding = SCENE_BINDING_OBJECT_TEXELS) uniform usamplerBuffer objectTexels;  // 4 texels per ObjectData
layout(set = 0, binding = SCENE_BINDING_MESH_TEXELS) uniform usamplerBuffer meshTexels;  // MESH_TEXELS per MeshData
layout(std430, set = 0, binding = SCENE_BINDING_INDICES) readonly buffer IndexBlock { uint indices[]; };
layout(set = 0, binding = SCENE_BINDING_TRIANGLE_TEXELS) uniform usamplerBuffer triangleTexels;
// The three indices of the triangle whose first index is `first` (a multiple of 3): one fetch where the scene has
// texels (on lavapipe each fetch is a load per lane, three times the fetches for the same bytes otherwise).
uvec3 triangleIndices(uint first) {
  if (VB_TEXELS != 0u) return texelFetch(triangleTexels, int(first / 3u)).xyz;
  return uvec3(indices[first], indices[first + 1u], indices[first + 2u]);
}
layout(std430, set = 0, binding = SCENE_BINDING_OBJECTS) readonly buffer ObjectBlock { ObjectData objects[]; };
layout(std430, set = 0, binding = SCENE_BINDING_OBJECTS_HIGH) readonly buffer ObjectBlockHigh { ObjectData objectsHigh[]; };

// Object records live in one buffer seen through two descriptor windows (each at most maxStorageBufferRange).
// (if/else, not ?: -- glslang emits an invalid store for a ternary over two blocks' structs.)
ObjectData objectAt(uint i) {
  if (VB_TEXELS != 0u) {
    int t = int(i) * 4;
    uvec4 w = texelFetch(objectTexels, t + 3);
    return ObjectData(uintBitsToFloat(texelFetch(objectTexels, t)), uintBitsToFloat(texelFetch(objectTexels, t + 1)),
                      uintBitsToFloat(texelFetch(objectTexels, t + 2)), w.x, w.y, uintBitsToFloat(w.z), w.w);
  }
  if (VB_WINDOWED == 0u || i < frame.objectSplit) {
    ObjectData o = objects[i];
    return o;
  }
  ObjectData o = objectsHigh[i - frame.objectSplit];
  return o;
}
layout(std430, set = 0, binding = SCENE_BINDING_MESHES) readonly buffer MeshBlock { MeshData meshes[]; };
#define MESH_TEXELS (3 + MAX_LODS)  // sizeof(MeshData) / 16: boundsSphere, 2 texels of fields, then one per LOD

vec4 meshBoundsSphere(uint mesh) {
  if (VB_TEXELS != 0u) return uintBitsToFloat(texelFetch(meshTexels, int(mesh * MESH_TEXELS)));
  return meshes[mesh].boundsSphere;
}

uint meshExtraOffset(uint mesh) {
  if (VB_TEXELS != 0u) return texelFetch(meshTexels, int(mesh * MESH_TEXELS + 1u)).w;
  return meshes[mesh].extraOffset;
}

LodData meshLod(uint mesh, uint lod) {
  if (VB_TEXELS != 0u) {
    uvec4 t = texelFetch(meshTexels, int(mesh * MESH_TEXELS + 3u + lod));
    return LodData(t.x, t.y, uintBitsToFloat(t.z), t.w);
  }
  return meshes[mesh].lods[lod];
}
layout(std430, set = 0, binding = SCENE_BINDING_VERTICES) readonly buffer VertexBlock0 { Vertex vertices0[]; };
layout(std430, set = 0, binding = SCENE_BINDING_VERTICES_1) readonly buffer VertexBlock1 { Vertex vertices1[]; };
layout(std430, set = 0, binding = SCENE_BINDING_VERTICES_2) readonly buffer VertexBlock2 { Vertex vertices2[]; };
layout(std430, set = 0, binding = SCENE_BINDING_VERTICES_3) readonly buffer VertexBlock3 { Vertex vertices3[]; };

// The vertex pool through its descriptor windows (each at most maxStorageBufferRange; skinned instances'
// regions make pools larger than one window).
Vertex vertexAt(uint i) {
  if (VB_TEXELS != 0u) {
    uvec4 a = texelFetch(vertexTexels, int(2u * i)), b = texelFetch(vertexTexels, int(2u * i + 1u));
    return Vertex(uintBitsToFloat(a.x), uintBitsToFloat(a.y), uintBitsToFloat(a.z), a.w, uintBitsToFloat(b.x),
                  uintBitsToFloat(b.y), b.z, b.w);
  }
  if (VB_WINDOWED == 0u) {
    Vertex v = vertices0[i];
    return v;
  }
  uint w = i >> frame.vertexWindowShift, j = i - (w << frame.vertexWindowShift);
  if (w == 0u) {
    Vertex v = vertices0[j];
    return v;
  }
  if (w == 1u) {
    Vertex v = vertices1[j];
    return v;
  }
  if (w == 2u) {
    Vertex v = vertices2[j];
    return v;
  }
  Vertex v = vertices3[j];
  return v;
}
layout(std430, set = 0, binding = SCENE_BINDING_VERTEX_EXTRAS) readonly buffer VertexExtraBlock { VertexExtra vertexExtras[]; };

// Skinned instances (gpu::Specialization::skinned; 0 for static scenes removes all of this): a skinned mesh slot
// keeps its rest mesh's vertexOffset (draws index the rest vertices, whose uv and colour stay) and addresses the
// instance's skinned positions, normals (and tangents) by buffer device address (skin.comp.glsl writes them).
layout(constant_id = 2) const uint VB_SKINNED = 0u;
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer SkinnedVertexRef { SkinnedVertex items[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer SkinnedTangentRef { uint items[]; };

// The position alone of meshVertex(mesh, i).position, loading only those three floats (the micro-raster's fetch:
// on lavapipe a whole-record load costs the other five words too).
vec3 meshPosition(uint mesh, uint i) {
  if (VB_SKINNED != 0u) {
    uvec2 a = uvec2(meshes[mesh].skinnedVertexLow, meshes[mesh].skinnedVertexHigh);
    if (a != uvec2(0u)) {
      uint k = i - meshes[mesh].vertexOffset;
      return vec3(SkinnedVertexRef(a).items[k].px, SkinnedVertexRef(a).items[k].py, SkinnedVertexRef(a).items[k].pz);
    }
  }
  if (VB_TEXELS != 0u) return uintBitsToFloat(texelFetch(vertexTexels, int(2u * i)).xyz);
  if (VB_WINDOWED == 0u) return vec3(vertices0[i].px, vertices0[i].py, vertices0[i].pz);
  uint w = i >> frame.vertexWindowShift, j = i - (w << frame.vertexWindowShift);
  if (w == 0u) return vec3(vertices0[j].px, vertices0[j].py, vertices0[j].pz);
  if (w == 1u) return vec3(vertices1[j].px, vertices1[j].py, vertices1[j].pz);
  if (w == 2u) return vec3(vertices2[j].px, vertices2[j].py, vertices2[j].pz);
  return vec3(vertices3[j].px, vertices3[j].py, vertices3[j].pz);
}

// Vertex i of the pool (a draw's vertexOffset + index) as mesh slot `mesh` has it: the rest vertex, with the
// skinned position and normal where the slot is a skinned instance's.
Vertex meshVertex(uint mesh, uint i) {
  Vertex v = vertexAt(i);
  if (VB_SKINNED != 0u) {
    uvec2 a = uvec2(meshes[mesh].skinnedVertexLow, meshes[mesh].skinnedVertexHigh);
    if (a != uvec2(0u)) {
      SkinnedVertex s = SkinnedVertexRef(a).items[i - meshes[mesh].vertexOffset];
      v.px = s.px;
      v.py = s.py;
      v.pz = s.pz;
      v.normal = s.normal;
    }
  }
  return v;
}

// The object-space tangent (octahedral) of mesh-local vertex `local` whose VertexExtra is `e`: the skinned one
// for a skinned instance's slot, else the rest one. Its w is always e.tangentW.
uint meshTangent(uint mesh, uint local, VertexExtra e) {
  if (VB_SKINNED != 0u) {
    uvec2 a = uvec2(meshes[mesh].skinnedTangentLow, meshes[mesh].skinnedTangentHigh);
    if (a != uvec2(0u)) return SkinnedTangentRef(a).items[local];
  }
  return e.tangent;
}
layout(std430, set = 0, binding = SCENE_BINDING_MATERIALS) readonly buffer MaterialBlock { MaterialData materials[]; };
layout(set = 0, binding = SCENE_BINDING_MATERIAL_TEXELS) uniform usamplerBuffer materialTexels;  // MATERIAL_TEXELS each
#define MATERIAL_TEXELS (4 + 3 * TEXTURE_SLOTS)  // sizeof(MaterialData) / 16

// Material record i (only the texels of the fields a shader uses are fetched: the rest is dead code).
MaterialData materialAt(uint i) {
  if (VB_TEXELS == 0u) return materials[i];
  int t = int(i * MATERIAL_TEXELS);
  uvec4 h = texelFetch(materialTexels, t + 3);
  MaterialData m;
  m.baseColor = uintBitsToFloat(texelFetch(materialTexels, t));
  m.emissive = uintBitsToFloat(texelFetch(materialTexels, t + 1));
  m.params = uintBitsToFloat(texelFetch(materialTexels, t + 2));
  m.flags = h.x;
  m.slotCount = h.y;
  m.clearcoat = uintBitsToFloat(h.z);
  m.clearcoatRoughness = uintBitsToFloat(h.w);
  for (int s = 0; s < TEXTURE_SLOTS; ++s) {
    uvec4 a = texelFetch(materialTexels, t + 4 + 3 * s);
    m.textures[s] = TextureSlotData(a.x, a.y, uintBitsToFloat(a.z), a.w, uintBitsToFloat(texelFetch(materialTexels, t + 5 + 3 * s)),
                                    uintBitsToFloat(texelFetch(materialTexels, t + 6 + 3 * s)));
  }
  return m;
}

// Object space -> camera-relative world space. The translation is made camera-relative first
// (anchor-relative translation + (anchor - camera)), so large coordinates cancel before the
// rotation/scale part is added.
vec3 objectToCamera(ObjectData o, vec3 p) {
  precise vec3 t = vec3(o.row0.w, o.row1.w, o.row2.w) + frame.cameraOffset.xyz;
  precise vec3 r = vec3(dot(o.row0.xyz, p), dot(o.row1.xyz, p), dot(o.row2.xyz, p));
  precise vec3 w = r + t;
  return w;
}

// The projection (FrameData.projection): orthographic or perspective. The functions below choose between the two
// with selects (mix with a boolean), never a branch: lavapipe in Mesa 22 recompiles a shader with a branch on
// uniform values alone at every bind (uniform_branch.glsl), and the micro-raster calls eyeInObjectSpace in its
// draw loop (a branch there made every micro-raster dispatch a 3.5 ms recompile).
bool orthographic() { return frame.projection.z != 0.0; }

// Reverse-Z depth at view distance d (= -z_view), and its inverse: perspective depth = B / d - A, orthographic
// B - A d (A = proj[2][2], B = proj[3][2]; an infinite perspective has A = 0, B = near).
float depthOfDistance(float d) {
  float A = frame.projection.x, B = frame.projection.y;
  return mix(B / d - A, B - A * d, orthographic());
}
float distanceOfDepth(float depth) {
  float A = frame.projection.x, B = frame.projection.y;
  return mix(B / (depth + A), (B - depth) / A, orthographic());
}

// The camera-relative world position seen at `ndc` with reverse-Z `depth` (the inverse of the projection; the
// view is rotation only, so its inverse is its transpose).
vec3 cameraRelativeAt(vec2 ndc, float depth) {
  float d = distanceOfDepth(depth);
  float s = mix(d, 1.0, orthographic());  // orthographic: x and y do not shrink with distance
  vec3 viewPos = vec3(ndc.x * s / frame.projX, ndc.y * s / frame.projY, -d);
  return transpose(mat3(frame.view)) * viewPos;
}

// The view direction's opposite in world space (towards the eye): the third row of the rotation-only view.
vec3 backwardsOfView() { return vec3(frame.view[0][2], frame.view[1][2], frame.view[2][2]); }

// Unit vector from the camera-relative point p towards the eye: perspective -normalize(p); orthographic the
// constant opposite of the view direction (every view ray is parallel to it).
vec3 towardsEye(vec3 p) { return mix(-normalize(p), backwardsOfView(), bvec3(orthographic())); }

// The eye in the object's space, homogeneous (the micro-raster's back-face pre-pass and the clusters' cone test):
// perspective (position, 1), the inverse of objectToCamera at the camera-relative origin; orthographic (direction,
// 0), the point at infinity towards the eye, so that q * eye.w - eye.xyz runs from the eye to q either way and a
// plane (n, w) faces the eye where dot(n, eye.xyz) + w * eye.w > 0.
vec4 eyeInObjectSpace(ObjectData o) {
  mat3 m = transpose(mat3(o.row0.xyz, o.row1.xyz, o.row2.xyz));  // columns: objectToCamera's linear part
  vec3 t = vec3(o.row0.w, o.row1.w, o.row2.w) + frame.cameraOffset.xyz;
  bool ortho = orthographic();
  return vec4(inverse(m) * mix(-t, backwardsOfView(), bvec3(ortho)), mix(1.0, 0.0, ortho));
}

// The clip position, computed identically by the visibility vertex shader, the shading pass and the
// forward vertex shader.
vec4 clipPosition(ObjectData o, vec3 p) {
  precise vec4 clip = frame.viewProj * vec4(objectToCamera(o, p), 1.0);
  return clip;
}

vec3 vertexPosition(Vertex v) { return vec3(v.px, v.py, v.pz); }

// Normal to world space with the inverse transpose of the 3x3 part (its cofactor matrix, scaled by
// sign(det)); not normalised, so that it commutes with interpolation.
vec3 normalToWorld(ObjectData o, vec3 n) {
  vec3 a = o.row0.xyz, b = o.row1.xyz, c = o.row2.xyz;
  vec3 bc = cross(b, c), ca = cross(c, a), ab = cross(a, b);
  float s = dot(a, bc) < 0.0 ? -1.0 : 1.0;
  return s * vec3(dot(bc, n), dot(ca, n), dot(ab, n));
}

// A direction (tangent) to world space: the linear part only, like a position difference.
vec3 objectToCameraVector(ObjectData o, vec3 v) { return vec3(dot(o.row0.xyz, v), dot(o.row1.xyz, v), dot(o.row2.xyz, v)); }

vec4 unpackColor(uint c) { return unpackUnorm4x8(c); }

#endif
