#version 460
// Visibility pass, vertex stage: pulls the vertex from the unified pool (gl_VertexIndex already
// includes the draw's vertexOffset); gl_InstanceIndex is firstInstance = object ID.
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_draw_parameters : require
#include "common.glsl"

layout(location = 0) flat out uint outDrawSlot;
layout(push_constant) uniform Push { PassConstants pc; };

void main() {
  ObjectData o = objectAt(gl_InstanceIndex);
  gl_Position = clipPosition(o, vertexPosition(vertexAt(gl_VertexIndex)));
  outDrawSlot = pc.drawBase + gl_DrawIDARB;  // late-phase draws follow the early ones
}
