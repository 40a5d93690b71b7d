#version 460
// Forward reference path, fragment stage. Variants: WRITE_IDS (also the IDs), COUNT_OVERDRAW (debug),
// ALPHA_MASK (masked draw lists: the same cut-out as the masked visibility raster), TRANSPARENT (the
// transparency pass: premultiplied colour and alpha for blending, glTF BLEND).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_samplerless_texture_functions : require
#include "raster_surface.glsl"
#include "shared/bindings_forward.h"
#if ALPHA_MASK || TRANSPARENT
#include "alpha_mask.glsl"
#endif

layout(location = 0) out vec4 outColor;
#if COUNT_OVERDRAW
#if !ALPHA_MASK
layout(early_fragment_tests) in;  // (not with discard: a cut-out fragment must not write depth)
#endif
layout(set = 1, binding = FORWARD_BINDING_OVERDRAW, r32ui) uniform coherent uimage2D overdraw;
#endif
#if WRITE_IDS
// Test/diagnostic variant: the same (object + 1, triangle) the visibility path decodes, so coverage can be
// compared pixel for pixel with the visibility buffer.
layout(location = 1) out uvec2 outId;
#endif

void main() {
  // The same material evaluation as the shading pass, with the hardware's screen derivatives.
  SurfaceInputs si = rasterSurfaceInputs();
#if ALPHA_MASK || TRANSPARENT
  float alpha = maskAlpha(inMaterial, si.uv0, si.uv1, si.duv0dx, si.duv0dy, si.duv1dx, si.duv1dy, inColor);
#endif
#if ALPHA_MASK
  if (maskCutsOut(inMaterial, alpha)) discard;
#endif
#if COUNT_OVERDRAW
  imageAtomicAdd(overdraw, ivec2(gl_FragCoord.xy), 1u);
#endif
  vec3 lit = shadeSurface(evaluateMaterial(inMaterial, si), uvec2(gl_FragCoord.xy));
#if TRANSPARENT
  outColor = vec4(lit * alpha, alpha);  // premultiplied: blended with ONE, ONE_MINUS_SRC_ALPHA
#else
  outColor = vec4(lit, 1.0);
#endif
#if WRITE_IDS
  outId = uvec2(inObject + 1u, uint(gl_PrimitiveID));
#endif
}
