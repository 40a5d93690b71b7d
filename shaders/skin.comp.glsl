#version 460
// Skinning pass: one thread per (animated instance, vertex). Linear blend skinning of the rest vertex's
// position, normal and tangent with the instance's joint matrices (skin space, 3 rows each), written as a
// 16-byte SkinnedVertex (and a 4-byte tangent where the mesh has tangents) to the instance's region, which
// its mesh slot addresses by buffer device address (MeshData.skinnedVertex*, skinnedTangent*): the raster, the
// shading pass and the forward path read it through meshVertex() in common.glsl. Uv, colour and the tangent's
// handedness stay the rest vertex's, so they are not copied per instance.
// Morph targets (si.morphTargets > 0) come first, as glTF orders them: the base position, normal and tangent
// plus the weighted deltas of every target with a non-zero weight (normal and tangent renormalised), then the
// skinning above; a morph-only mesh has a one-joint skin whose joint is its node.
// Thread 0 of each instance writes the instance's LOD errors scaled by the pose, and with joint-reach bounds
// the CPU's sphere (animation.h). With GPU bounds (pc.material & SKIN_MODE_GPU_BOUNDS) every subgroup reduces its
// skinned positions to an AABB and merges it into the instance's bounds record with 6 atomicMin; the
// RESOLVE_BOUNDS variant (skin_bounds.comp, after this pass) turns that AABB into the slot's sphere.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#include "shared/types.h"
#include "octahedral.glsl"

#ifndef RESOLVE_BOUNDS
#define RESOLVE_BOUNDS 0
#endif

layout(local_size_x = SKIN_WORKGROUP_SIZE) in;

layout(std430, set = 0, binding = SKIN_BINDING_MESHES) buffer MeshBlock { MeshData meshes[]; };
layout(std430, set = 0, binding = SKIN_BINDING_INSTANCES) readonly buffer InstanceBlock { SkinInstance instances[]; };
layout(std430, set = 0, binding = SKIN_BINDING_BOUNDS) buffer BoundsBlock { uint bounds[]; };
layout(push_constant) uniform Push { PassConstants pc; };  // phase: instance count, drawBase: window shift

// Floats ordered as uints: a < b (not NaN) exactly when orderedFloat(a) < orderedFloat(b).
uint orderedFloat(float f) {
  uint u = floatBitsToUint(f);
  return (u & 0x80000000u) != 0u ? ~u : u | 0x80000000u;
}
float orderedFloatInverse(uint u) { return uintBitsToFloat((u & 0x80000000u) != 0u ? u & 0x7fffffffu : ~u); }

#if RESOLVE_BOUNDS
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer SkinnedVertexRef { SkinnedVertex items[]; };

// The sphere of GPU bounds, after the skinning pass reduced each instance's AABB, in three steps (pc.variant):
//  SKIN_BOUNDS_CENTRE (one thread per instance): the AABB centre c -> the mesh slot's boundsSphere.xyz;
//  SKIN_BOUNDS_DISTANCE (one thread per instance vertex, dispatched like the skinning): the largest |p - c| of
//    the instance's skinned vertices, reduced per subgroup, then atomicMin of orderedFloat(-distance);
//  SKIN_BOUNDS_RADIUS (one thread per instance): that distance, widened by 1e-5 relative and 1e-6 of the
//    centre's magnitude (far above the few ulps of rounding in p - c and length()) -> boundsSphere.w.
// So the radius is the tightest about the AABB centre, not the AABB's half diagonal (up to sqrt(3) larger).
void main() {
  uint b;
  if (pc.variant == SKIN_BOUNDS_DISTANCE) {
    uint inst = gl_WorkGroupID.y + gl_WorkGroupID.z * 65535u;
    if (inst >= pc.phase) return;
    uint slot = instances[inst].meshSlot;
    uint v = gl_GlobalInvocationID.x;
    if (v >= instances[inst].vertexCount) return;
    SkinnedVertex s = SkinnedVertexRef(uvec2(meshes[slot].skinnedVertexLow, meshes[slot].skinnedVertexHigh)).items[v];
    float d = length(vec3(s.px, s.py, s.pz) - meshes[slot].boundsSphere.xyz);
    uint m = subgroupMin(orderedFloat(-d));
    if (subgroupElect()) atomicMin(bounds[SKIN_BOUNDS_UINTS * inst + 6u], m);
    return;
  }
  uint inst = gl_GlobalInvocationID.x;
  if (inst >= pc.phase) return;
  b = SKIN_BOUNDS_UINTS * inst;
  uint slot = instances[inst].meshSlot;
  if (pc.variant == SKIN_BOUNDS_CENTRE) {
    vec3 lo = vec3(orderedFloatInverse(bounds[b]), orderedFloatInverse(bounds[b + 1u]), orderedFloatInverse(bounds[b + 2u]));
    vec3 hi = -vec3(orderedFloatInverse(bounds[b + 3u]), orderedFloatInverse(bounds[b + 4u]),
                    orderedFloatInverse(bounds[b + 5u]));
    meshes[slot].boundsSphere = vec4(0.5 * lo + 0.5 * hi, 0.0);
  } else {
    vec3 c = meshes[slot].boundsSphere.xyz;
    float r = -orderedFloatInverse(bounds[b + 6u]);
    meshes[slot].boundsSphere.w = r * (1.0 + 1e-5) + 1e-6 * max(max(abs(c.x), abs(c.y)), abs(c.z));
  }
}
#else

struct SkinVertexData {  // scene/skin_vertex.h: 8 x uint16 joints, 8 x float weights (48 bytes)
  uint joints[4];         // two 16-bit joint indices each, slot 2k in the low half
  float weights[8];
};

layout(std430, set = 0, binding = SKIN_BINDING_VERTICES) readonly buffer VertexBlock0 { Vertex vertices0[]; };
layout(std430, set = 0, binding = SKIN_BINDING_VERTICES_1) readonly buffer VertexBlock1 { Vertex vertices1[]; };
layout(std430, set = 0, binding = SKIN_BINDING_VERTICES_2) readonly buffer VertexBlock2 { Vertex vertices2[]; };
layout(std430, set = 0, binding = SKIN_BINDING_VERTICES_3) readonly buffer VertexBlock3 { Vertex vertices3[]; };
layout(std430, set = 0, binding = SKIN_BINDING_SKIN_VERTICES) readonly buffer SkinBlock { SkinVertexData skin[]; };
layout(std430, set = 0, binding = SKIN_BINDING_JOINTS) readonly buffer JointBlock { vec4 jointRows[]; };
layout(std430, set = 0, binding = SKIN_BINDING_EXTRAS) readonly buffer ExtraBlock { VertexExtra vertexExtras[]; };
layout(std430, set = 0, binding = SKIN_BINDING_MORPH_DELTAS) readonly buffer MorphBlock { MorphDelta morphDeltas[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer SkinnedVertexRef { SkinnedVertex items[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer SkinnedTangentRef { uint items[]; };

// The rest vertices through the pool's windows, as vertexAt() in common.glsl (the shift comes as a push
// constant here).
Vertex loadVertex(uint i) {
  uint w = i >> pc.drawBase, j = i - (w << pc.drawBase);
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

void main() {
  uint inst = gl_WorkGroupID.y + gl_WorkGroupID.z * 65535u;
  if (inst >= pc.phase) return;
  SkinInstance si = instances[inst];
  const bool gpuBounds = (pc.material & SKIN_MODE_GPU_BOUNDS) != 0u;
  uint v = gl_GlobalInvocationID.x;
  if (v == 0u) {
    if (!gpuBounds) meshes[si.meshSlot].boundsSphere = si.bounds;
    for (uint k = 0u; k < meshes[si.meshSlot].lodCount; ++k)
      meshes[si.meshSlot].lods[k].error = meshes[si.sourceMesh].lods[k].error * si.lodScale;
  }
  if (v >= si.vertexCount) return;
  Vertex rest = loadVertex(si.sourceVertex + v);
  SkinVertexData s = skin[si.skinVertex + v];
  // All 8 influences (glTF JOINTS_0/1, WEIGHTS_0/1) in slot order; slots of weight 0 (every slot past the 4th
  // of a 4-influence mesh) fetch no joint.
  vec4 r0 = vec4(0.0), r1 = vec4(0.0), r2 = vec4(0.0);
  for (int i = 0; i < 8; ++i) {
    float w = s.weights[i];
    if (w == 0.0) continue;
    uint j = (s.joints[i >> 1] >> (16u * uint(i & 1))) & 0xFFFFu;
    uint base = 3u * (si.firstJoint + j);
    r0 += w * jointRows[base];
    r1 += w * jointRows[base + 1u];
    r2 += w * jointRows[base + 2u];
  }
  vec4 p = vec4(rest.px, rest.py, rest.pz, 1.0);
  vec3 n = octDecode(rest.normal);
  uvec2 tangents = uvec2(meshes[si.meshSlot].skinnedTangentLow, meshes[si.meshSlot].skinnedTangentHigh);
  VertexExtra e;
  e.tangentW = 0.0;
  if (tangents != uvec2(0u)) e = vertexExtras[si.sourceExtra + v];
  vec3 restTangent = e.tangentW != 0.0 ? octDecode(e.tangent) : vec3(0.0);
  if (si.morphTargets > 0u) {
    vec3 dp = vec3(0.0), dn = vec3(0.0), dt = vec3(0.0);
    for (uint t = 0u; t < si.morphTargets; ++t) {
      float mw = jointRows[si.morphWeightRow + t / 4u][t % 4u];
      if (mw == 0.0) continue;
      MorphDelta d = morphDeltas[si.firstMorphDelta + t * si.vertexCount + v];
      dp += mw * vec3(d.px, d.py, d.pz);
      dn += mw * vec3(d.nx, d.ny, d.nz);
      dt += mw * vec3(d.tx, d.ty, d.tz);
    }
    p.xyz += dp;
    vec3 mn = n + dn;
    n = dot(mn, mn) > 0.0 ? normalize(mn) : n;  // a delta cancelling the normal: keep the base one
    if (e.tangentW != 0.0) {
      vec3 mt = restTangent + dt;
      restTangent = dot(mt, mt) > 0.0 ? normalize(mt) : restTangent;
    }
  }
  // Normal: the cofactor of the blended 3x3 (inverse transpose up to scale), signed by its determinant.
  vec3 a = r0.xyz, b = r1.xyz, c = r2.xyz;
  vec3 bc = cross(b, c), ca = cross(c, a), ab = cross(a, b);
  vec3 sn = (dot(a, bc) < 0.0 ? -1.0 : 1.0) * vec3(dot(bc, n), dot(ca, n), dot(ab, n));
  SkinnedVertex o;
  o.px = dot(r0, p);
  o.py = dot(r1, p);
  o.pz = dot(r2, p);
  o.normal = octEncode(normalize(sn));
  SkinnedVertexRef(uvec2(meshes[si.meshSlot].skinnedVertexLow, meshes[si.meshSlot].skinnedVertexHigh)).items[v] = o;
  // Tangent: a direction on the surface, so the blended 3x3 itself (like a position difference); w (the
  // bitangent's handedness) is the rest vertex's, read from its VertexExtra by every reader. (A blend with a
  // negative determinant -- a mirroring joint scale, in none of our assets -- would need w * sign(det).)
  if (tangents != uvec2(0u)) {
    uint t = 0u;
    if (e.tangentW != 0.0) {
      vec3 rt = restTangent;
      t = octEncode(normalize(vec3(dot(a, rt), dot(b, rt), dot(c, rt))));
    }
    SkinnedTangentRef(tangents).items[v] = t;
  }
  if (gpuBounds) {  // this subgroup's AABB, one atomic per component (uniform branch: a push constant)
    uint x = subgroupMin(orderedFloat(o.px)), y = subgroupMin(orderedFloat(o.py)), z = subgroupMin(orderedFloat(o.pz));
    uint nx = subgroupMin(orderedFloat(-o.px)), ny = subgroupMin(orderedFloat(-o.py)),
         nz = subgroupMin(orderedFloat(-o.pz));
    if (subgroupElect()) {
      uint bb = SKIN_BOUNDS_UINTS * inst;
      atomicMin(bounds[bb], x);
      atomicMin(bounds[bb + 1u], y);
      atomicMin(bounds[bb + 2u], z);
      atomicMin(bounds[bb + 3u], nx);
      atomicMin(bounds[bb + 4u], ny);
      atomicMin(bounds[bb + 5u], nz);
    }
  }
}
#endif
