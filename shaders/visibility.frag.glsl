#version 460
// Visibility pass, fragment stage: writes the draw slot and the triangle index within the draw
// (gl_PrimitiveID restarts at 0 for every draw of a multi-draw). 0 is reserved for "nothing".
//   narrow (r32ui): ((slot << triangleBits) | triangle) + 1, chosen only when it cannot wrap;
//   wide (rg32ui, WIDE_IDS): x = slot + 1, y = triangle.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

#if COUNT_OVERDRAW
// Debug variant: count the raster writes per pixel (fragments that pass the depth test when they run).
layout(early_fragment_tests) in;
layout(set = 0, binding = BINDING_OVERDRAW, r32ui) uniform coherent uimage2D overdraw;
#endif
layout(location = 0) flat in uint inDrawSlot;
#if WIDE_IDS
layout(location = 0) out uvec2 outId;
#else
layout(location = 0) out uint outId;
#endif

void main() {
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
