#version 460
// Forward reference path, vertex stage: same pulled vertex and same clip math as the visibility
// pass; attributes are interpolated by the hardware (the accuracy reference for the shading pass).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) out vec3 outNormal;  // world, not normalised (interpolation commutes with it)
layout(location = 1) out vec4 outColor;
layout(location = 2) flat out uint outMaterial;
layout(location = 3) flat out uint outObject;
layout(location = 4) out vec3 outPosition;  // camera-relative world
layout(location = 5) out vec4 outUv;        // TEXCOORD_0, TEXCOORD_1
layout(location = 6) out vec4 outTangent;   // world xyz, w: bitangent sign (0: none)

void main() {
  ObjectData o = objectAt(gl_InstanceIndex);
  Vertex v = meshVertex(o.meshIndex, gl_VertexIndex);
  gl_Position = clipPosition(o, vertexPosition(v));
  outPosition = objectToCamera(o, vertexPosition(v));
  outNormal = normalToWorld(o, octDecode(v.normal));
  outColor = unpackColor(v.color);
  outMaterial = o.materialIndex;
  outObject = gl_InstanceIndex;
  outUv = vec4(v.u, v.v, 0.0, 0.0);
  outTangent = vec4(0.0);
  uint extra = meshes[o.meshIndex].extraOffset;
  if (VB_EXTRAS != 0u && extra != EXTRA_NONE) {
    uint local = uint(gl_VertexIndex) - meshes[o.meshIndex].vertexOffset;
    VertexExtra e = vertexExtras[extra + local];
    outUv.zw = vec2(e.u1, e.v1);
    if (e.tangentW != 0.0)
      outTangent = vec4(objectToCameraVector(o, octDecode(meshTangent(o.meshIndex, local, e))), e.tangentW);
  }
}
