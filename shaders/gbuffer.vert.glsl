#version 460
// G-buffer baseline, vertex stage: the visibility pass's indirect draws (same pulled vertex, same clipPosition(),
// so coverage and depth match the visibility buffer), plus the attributes the fragment stage stores.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) out vec3 outNormal;  // world, not normalised (interpolation commutes with it)
layout(location = 1) out vec4 outColor;   // vertex colour
layout(location = 2) flat out uint outMaterial;
layout(location = 3) out vec3 outPosition;  // camera-relative world (for material evaluation)

void main() {
  ObjectData o = objectAt(gl_InstanceIndex);  // firstInstance = object ID, as in the visibility pass
  Vertex v = vertexAt(gl_VertexIndex);
  gl_Position = clipPosition(o, vertexPosition(v));
  outPosition = objectToCamera(o, vertexPosition(v));
  outNormal = normalToWorld(o, octDecode(v.normal));
  outColor = unpackColor(v.color);
  outMaterial = o.materialIndex;
}
