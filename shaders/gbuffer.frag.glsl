#version 460
// G-buffer baseline, fragment stage (vertex stage: forward.vert): evaluates the material once per depth-passing
// fragment (the cost the visibility buffer avoids under overdraw), with the hardware's derivatives as the forward
// path, and stores the surface in the usual attribute targets:
//   RT0 rgba8 sRGB   base colour (linear in the shader, sRGB-encoded by the target), alpha
//   RT1 rg16 snorm   unit world normal (after normal mapping), octahedral (octahedral.glsl), or rg16f where snorm
//                    cannot be rendered to
//   RT2 rgba8 unorm  metallic, roughness, occlusion, 1 where unlit (KHR_materials_unlit)
//   RT3 b10g11r11    emissive radiance (rgba16f where that format cannot be rendered to)
//   RT4 rgba16f      KHR_materials_clearcoat: the coat's octahedral normal, roughness, weight (r8 unorm, unread,
//                    in scenes without a coated material)
// plus the D32 reverse-Z depth, from which gbuffer_lighting.comp rebuilds the position.
// ALPHA_MASK variant (masked draw lists): the same cut-out as the masked visibility raster.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_samplerless_texture_functions : require
#include "raster_surface.glsl"
#include "shared/bindings_gbuffer.h"
#if ALPHA_MASK
#include "alpha_mask.glsl"
#endif

layout(location = 0) out vec4 outBaseColor;
layout(location = 1) out vec2 outNormal;
layout(location = 2) out vec4 outMaterial;
layout(location = 3) out vec4 outEmissive;
layout(location = 4) out vec4 outCoat;
#if COUNT_OVERDRAW
#if !ALPHA_MASK
layout(early_fragment_tests) in;  // (not with discard: a cut-out fragment must not write depth)
#endif
// Debug/bandwidth variant: count the raster writes per pixel (fragments that pass the depth test when they run).
layout(set = 1, binding = GBUFFER_BINDING_OVERDRAW, r32ui) uniform coherent uimage2D overdraw;
#endif

void main() {
  SurfaceInputs si = rasterSurfaceInputs();
#if ALPHA_MASK
  float alpha = maskAlpha(inMaterial, si.uv0, si.uv1, si.duv0dx, si.duv0dy, si.duv1dx, si.duv1dy, inColor);
  if (maskCutsOut(inMaterial, alpha)) discard;
#endif
#if COUNT_OVERDRAW
  imageAtomicAdd(overdraw, ivec2(gl_FragCoord.xy), 1u);
#endif
  Surface s = evaluateMaterial(inMaterial, si);
  outBaseColor = vec4(s.baseColor, s.alpha);
  outNormal = unpackSnorm2x16(octEncode(s.normal));  // exactly representable in snorm16
  outMaterial = vec4(s.metallic, s.roughness, s.occlusion, surfaceUnlit(s) ? 1.0 : 0.0);
  outEmissive = vec4(s.emissive, 0.0);
  outCoat = vec4(unpackSnorm2x16(octEncode(s.clearcoatNormal)), s.clearcoatRoughness, s.clearcoat);
}
