#version 460
// Software micro-raster merge, fragment stage: the micro-raster's nearest fragment of this pixel (if any) becomes
// an ordinary visibility fragment -- its depth through gl_FragDepth, tested GREATER (reverse-Z) against what the
// hardware raster left, and its ID in the target's encoding -- so the pyramid, the late phase, the shading and the
// transparency pass see one target. On equal depth the hardware fragment stays.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "common.glsl"
#include "shared/bindings_sw_raster.h"

layout(std430, set = 1, binding = SW_RASTER_BINDING_VISIBILITY) readonly buffer SwBlock { uint64_t swVisibility[]; };
#if WIDE_IDS
layout(location = 0) out uvec2 outId;
#else
layout(location = 0) out uint outId;
#endif

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  uint64_t v = swVisibility[uint(p.y) * uint(frame.viewport.x) + uint(p.x)];
  uint depthBits = uint(v >> 32);
  if (depthBits == 0u) discard;
  uint payload = ~uint(v & 0xffffffffUL);  // (stored complemented: equal depths keep the lowest payload)
  gl_FragDepth = uintBitsToFloat(depthBits);
#if WIDE_IDS
  outId = uvec2((payload >> frame.swTriangleBits) + 1u, payload & ((1u << frame.swTriangleBits) - 1u));
#else
  outId = payload;
#endif
}
