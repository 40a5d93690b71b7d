#version 460
#extension GL_GOOGLE_include_directive : require
#include "lighting.glsl"

layout(location = 0) in vec3 inNormal;
layout(location = 1) in vec4 inColor;
layout(location = 2) flat in uint inMaterial;
layout(location = 3) flat in uint inObject;
layout(location = 4) in vec3 inPosition;  // camera-relative world
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
  outColor = vec4(shadeSurface(factorSurface(inMaterial, inPosition, normalize(inNormal), inColor), uvec2(gl_FragCoord.xy)), 1.0);
#if WRITE_IDS
  outId = uvec2(inObject + 1u, uint(gl_PrimitiveID));
#endif
}
