#version 460
// Visibility pass, vertex stage: pulls the vertex from the unified pool (gl_VertexIndex already
// includes the draw's vertexOffset); gl_InstanceIndex is firstInstance = object ID.
// ALPHA_MASK variant (masked draw lists): also the material and what maskAlpha() needs, interpolated.
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_draw_parameters : require
#include "common.glsl"

layout(location = 0) flat out uint outDrawSlot;
#if ALPHA_MASK
layout(location = 1) flat out uint outMaterial;
layout(location = 2) out vec2 outUv0;
layout(location = 3) out vec2 outUv1;
layout(location = 4) out vec4 outColor;
#endif
layout(push_constant) uniform Push { PassConstants pc; };

void main() {
  ObjectData o = objectAt(gl_InstanceIndex);
  Vertex v = meshVertex(o.meshIndex, gl_VertexIndex);
  gl_Position = clipPosition(o, vertexPosition(v));
  outDrawSlot = pc.drawBase + gl_DrawIDARB;  // late-phase draws follow the early ones
#if ALPHA_MASK
  outMaterial = o.materialIndex;
  outUv0 = vec2(v.u, v.v);
  outUv1 = vec2(0.0);
  uint extra = meshes[o.meshIndex].extraOffset;
  if (VB_EXTRAS != 0u && extra != EXTRA_NONE) {
    VertexExtra e = vertexExtras[extra + uint(gl_VertexIndex) - meshes[o.meshIndex].vertexOffset];
    outUv1 = vec2(e.u1, e.v1);
  }
  outColor = unpackColor(v.color);
#endif
}
