#version 460
// Visibility pass, fragment stage: writes the draw slot and the triangle index within the draw
// (gl_PrimitiveID restarts at 0 for every draw of a multi-draw). 0 is reserved for "nothing".
//   narrow (r32ui): ((slot << triangleBits) | triangle) + 1, chosen only when it cannot wrap;
//   wide (rg32ui, WIDE_IDS): x = slot + 1, y = triangle.
// ALPHA_MASK variant (masked draw lists): fragments whose maskAlpha() is below the cutoff are discarded,
// before they write depth or an ID.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_samplerless_texture_functions : require
#include "common.glsl"
#include "shared/bindings_visibility.h"
#if ALPHA_MASK
#include "alpha_mask.glsl"
#endif

#if COUNT_OVERDRAW
// Debug variant: count the raster writes per pixel (fragments that pass the depth test when they run).
// The masked variant cannot test depth early (a discarded fragment must not write depth): it counts the
// fragments that survive the alpha test, before the depth test.
#if !ALPHA_MASK
layout(early_fragment_tests) in;
#endif
layout(set = 1, binding = VISIBILITY_BINDING_OVERDRAW, r32ui) uniform coherent uimage2D overdraw;
#endif
layout(location = 0) flat in uint inDrawSlot;
#if ALPHA_MASK
layout(location = 1) flat in uint inMaterial;
layout(location = 2) in vec2 inUv0;
layout(location = 3) in vec2 inUv1;
layout(location = 4) in vec4 inColor;
#endif
#if WIDE_IDS
layout(location = 0) out uvec2 outId;
#else
layout(location = 0) out uint outId;
#endif

void main() {
#if ALPHA_MASK
  float alpha = maskAlpha(inMaterial, inUv0, inUv1, dFdx(inUv0), dFdy(inUv0), dFdx(inUv1), dFdy(inUv1), inColor);
  if (maskCutsOut(inMaterial, alpha)) discard;
#endif
#if COUNT_OVERDRAW
  imageAtomicAdd(overdraw, ivec2(gl_FragCoord.xy), 1u);
#endif
  uint tri = uint(gl_PrimitiveID);
#if WIDE_IDS
  outId = uvec2(inDrawSlot + 1u, tri);
#else
  outId = ((inDrawSlot << frame.triangleBits) | tri) + 1u;
#endif
}
