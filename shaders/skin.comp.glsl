#version 460
// Skinning pass: one thread per (animated instance, vertex). Linear blend skinning of the rest vertex's
// position and normal with the instance's joint matrices (skin space, 3 rows each), written into the
// instance's own region of the unified vertex pool, which its draws (and the shading pass) read like any
// static mesh. Thread 0 of each instance also writes the instance's mesh slot: the pose's conservative
// bounding sphere and the LOD errors scaled by the pose (the CPU computed both, animation.h).
#extension GL_GOOGLE_include_directive : require
#include "shared/types.h"
#include "octahedral.glsl"

layout(local_size_x = SKIN_WORKGROUP_SIZE) in;

struct SkinVertexData {  // scene/skin_vertex.h: 4 x uint16 joints, 4 x float weights (24 bytes)
  uint joints01;
  uint joints23;
  float w0, w1, w2, w3;
};

layout(std430, set = 0, binding = SKIN_BINDING_VERTICES) buffer VertexBlock0 { Vertex vertices0[]; };
layout(std430, set = 0, binding = SKIN_BINDING_VERTICES_1) buffer VertexBlock1 { Vertex vertices1[]; };
layout(std430, set = 0, binding = SKIN_BINDING_VERTICES_2) buffer VertexBlock2 { Vertex vertices2[]; };
layout(std430, set = 0, binding = SKIN_BINDING_VERTICES_3) buffer VertexBlock3 { Vertex vertices3[]; };
layout(std430, set = 0, binding = SKIN_BINDING_MESHES) buffer MeshBlock { MeshData meshes[]; };
layout(std430, set = 0, binding = SKIN_BINDING_SKIN_VERTICES) readonly buffer SkinBlock { SkinVertexData skin[]; };
layout(std430, set = 0, binding = SKIN_BINDING_JOINTS) readonly buffer JointBlock { vec4 jointRows[]; };
layout(std430, set = 0, binding = SKIN_BINDING_INSTANCES) readonly buffer InstanceBlock { SkinInstance instances[]; };
layout(push_constant) uniform Push { PassConstants pc; };  // phase: instance count, drawBase: window shift

// The vertex pool's windows, as vertexAt() in common.glsl (the shift comes as a push constant here).
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

void storeVertex(uint i, Vertex v) {
  uint w = i >> pc.drawBase, j = i - (w << pc.drawBase);
  if (w == 0u) vertices0[j] = v;
  else if (w == 1u) vertices1[j] = v;
  else if (w == 2u) vertices2[j] = v;
  else vertices3[j] = v;
}

void main() {
  uint inst = gl_WorkGroupID.y + gl_WorkGroupID.z * 65535u;
  if (inst >= pc.phase) return;
  SkinInstance si = instances[inst];
  uint v = gl_GlobalInvocationID.x;
  if (v == 0u) {
    meshes[si.meshSlot].boundsSphere = si.bounds;
    for (uint k = 0u; k < meshes[si.meshSlot].lodCount; ++k)
      meshes[si.meshSlot].lods[k].error = meshes[si.sourceMesh].lods[k].error * si.lodScale;
  }
  if (v >= si.vertexCount) return;
  Vertex rest = loadVertex(si.sourceVertex + v);
  SkinVertexData s = skin[si.skinVertex + v];
  uint j[4] = uint[](s.joints01 & 0xFFFFu, s.joints01 >> 16, s.joints23 & 0xFFFFu, s.joints23 >> 16);
  float w[4] = float[](s.w0, s.w1, s.w2, s.w3);
  vec4 r0 = vec4(0.0), r1 = vec4(0.0), r2 = vec4(0.0);
  for (int i = 0; i < 4; ++i) {
    if (w[i] == 0.0) continue;
    uint base = 3u * (si.firstJoint + j[i]);
    r0 += w[i] * jointRows[base];
    r1 += w[i] * jointRows[base + 1u];
    r2 += w[i] * jointRows[base + 2u];
  }
  vec4 p = vec4(rest.px, rest.py, rest.pz, 1.0);
  // Normal: the cofactor of the blended 3x3 (inverse transpose up to scale), signed by its determinant.
  vec3 a = r0.xyz, b = r1.xyz, c = r2.xyz;
  vec3 bc = cross(b, c), ca = cross(c, a), ab = cross(a, b);
  vec3 n = octDecode(rest.normal);
  vec3 sn = (dot(a, bc) < 0.0 ? -1.0 : 1.0) * vec3(dot(bc, n), dot(ca, n), dot(ab, n));
  Vertex o = rest;
  o.px = dot(r0, p);
  o.py = dot(r1, p);
  o.pz = dot(r2, p);
  o.normal = octEncode(normalize(sn));
  storeVertex(si.outVertex + v, o);
}
