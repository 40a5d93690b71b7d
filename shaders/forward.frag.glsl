#version 460
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) in vec3 inNormal;
layout(location = 1) in vec4 inColor;
layout(location = 2) flat in uint inMaterial;
layout(location = 0) out vec4 outColor;

void main() {
  vec4 baseColor = materials[inMaterial].baseColor * inColor;
  outColor = vec4(shadeSurface(normalize(inNormal), baseColor.rgb), 1.0);
}
