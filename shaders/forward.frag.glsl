#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_samplerless_texture_functions : require
#include "material.glsl"

layout(location = 0) in vec3 inNormal;
layout(location = 1) in vec4 inColor;
layout(location = 2) flat in uint inMaterial;
layout(location = 3) flat in uint inObject;
layout(location = 4) in vec3 inPosition;  // camera-relative world
layout(location = 5) in vec4 inUv;
layout(location = 6) in vec4 inTangent;
layout(location = 0) out vec4 outColor;
#if COUNT_OVERDRAW
layout(early_fragment_tests) in;
layout(set = 0, binding = BINDING_OVERDRAW, r32ui) uniform coherent uimage2D overdraw;
#endif
#if WRITE_IDS
// Test/diagnostic variant: the same (object + 1, triangle) the visibility path decodes, so coverage can be
// compared pixel for pixel with the visibility buffer.
layout(location = 1) out uvec2 outId;
#endif

void main() {
#if COUNT_OVERDRAW
  imageAtomicAdd(overdraw, ivec2(gl_FragCoord.xy), 1u);
#endif
  // The same material evaluation as the shading pass, with the hardware's screen derivatives.
  SurfaceInputs si;
  si.position = inPosition;
  si.normal = inNormal;
  si.tangent = inTangent;
  si.dpdx = dFdx(inPosition);
  si.dpdy = dFdy(inPosition);
  si.uv0 = inUv.xy;
  si.uv1 = inUv.zw;
  si.duv0dx = dFdx(inUv.xy);
  si.duv0dy = dFdy(inUv.xy);
  si.duv1dx = dFdx(inUv.zw);
  si.duv1dy = dFdy(inUv.zw);
  si.color = inColor;
  si.frontFacing = gl_FrontFacing;
  outColor = vec4(shadeSurface(evaluateMaterial(inMaterial, si), uvec2(gl_FragCoord.xy)), 1.0);
#if WRITE_IDS
  outId = uvec2(inObject + 1u, uint(gl_PrimitiveID));
#endif
}
