#version 460
// G-buffer baseline, fragment stage: evaluates the surface once per depth-passing fragment (the cost the
// visibility buffer avoids under overdraw) and stores it in the usual attribute targets:
//   RT0 rgba8 sRGB   base colour (linear in the shader, sRGB-encoded by the target), alpha
//   RT1 rg16 snorm   unit world normal, octahedral (octahedral.glsl), or rg16f where snorm cannot be rendered to
//   RT2 rgba8 unorm  metallic, roughness, occlusion, unused
//   RT3 b10g11r11    emissive radiance (rgba16f where that format cannot be rendered to)
// plus the D32 reverse-Z depth, from which gbuffer_lighting.comp rebuilds the position.
#extension GL_GOOGLE_include_directive : require
#include "lighting.glsl"

layout(location = 0) in vec3 inNormal;
layout(location = 1) in vec4 inColor;
layout(location = 2) flat in uint inMaterial;
layout(location = 3) in vec3 inPosition;
layout(location = 0) out vec4 outBaseColor;
layout(location = 1) out vec2 outNormal;
layout(location = 2) out vec4 outMaterial;
layout(location = 3) out vec4 outEmissive;
#if COUNT_OVERDRAW
// Debug/bandwidth variant: count the raster writes per pixel (fragments that pass the depth test when they run).
layout(early_fragment_tests) in;
layout(set = 0, binding = BINDING_OVERDRAW, r32ui) uniform coherent uimage2D overdraw;
#endif

// The surface this path stores. Until shaders/material.glsl lands on this branch it is what the forward and
// visibility paths shade (plainSurface from materials[m].baseColor x vertex colour) plus the material's metallic
// and roughness factors (not read by shadeSurface yet); at merge time this becomes evaluateMaterial().
Surface gbufferSurface(uint m, vec3 position, vec3 normal, vec4 color) {
  vec4 baseColor = materials[m].baseColor * color;
  Surface s = plainSurface(position, normal, baseColor.rgb);
  s.alpha = baseColor.a;
  s.metallic = materials[m].params.x;
  s.roughness = materials[m].params.y;
  return s;
}

void main() {
#if COUNT_OVERDRAW
  imageAtomicAdd(overdraw, ivec2(gl_FragCoord.xy), 1u);
#endif
  Surface s = gbufferSurface(inMaterial, inPosition, normalize(inNormal), inColor);
  outBaseColor = vec4(s.baseColor, s.alpha);
  outNormal = unpackSnorm2x16(octEncode(s.normal));  // exactly representable in snorm16
  outMaterial = vec4(s.metallic, s.roughness, s.occlusion, 0.0);
  outEmissive = vec4(s.emissive, 0.0);
}
