#version 460
// Software micro-raster merge, fragment stage: the micro-raster's nearest fragment of this pixel (if any) becomes
// an ordinary visibility fragment -- its depth through gl_FragDepth, tested GREATER (reverse-Z) against what the
// hardware raster left, and its ID in the target's encoding -- so the pyramid, the late phase, the shading and the
// transparency pass see one target. On equal depth the hardware fragment stays.
#extension GL_GOOGLE_include_directive : require
#include "sw_payload.glsl"
#include "shared/bindings_sw_raster.h"

layout(set = 1, binding = SW_RASTER_BINDING_VISIBILITY_TEXELS) uniform usamplerBuffer swTexels;
#if WIDE_IDS
layout(location = 0) out uvec2 outId;
#else
layout(location = 0) out uint outId;
#endif

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  // (x: the complemented payload, y: the depth bits; through the texel view, bindings_sw_raster.h)
  uvec2 v = texelFetch(swTexels, p.y * int(frame.viewport.x) + p.x).xy;
  uint depthBits = v.y;
  if (depthBits == 0u) discard;
  gl_FragDepth = uintBitsToFloat(depthBits);
#if WIDE_IDS
  outId = microRasterId(v.x);
#else
  outId = microRasterId(v.x).x;
#endif
}
