// The micro-raster's payload (sw_raster.comp), stored complemented beside its depth bits, and the raw ID of the
// visibility target's encoding it stands for (FrameData.wideIds / triangleBits / swTriangleBits): written by the
// merge (sw_merge.frag) and by the resolve (visibility_id.glsl) in the one way this file gives.
#ifndef VISBUF_SW_PAYLOAD_GLSL
#define VISBUF_SW_PAYLOAD_GLSL

#include "common.glsl"

// Triangle t of draw `slot`. Lower payloads are earlier in draw order (lower slot, then lower triangle).
// (Selects, not branches, on the frame's values: uniform_branch.glsl says why.)
uint microRasterPayload(uint slot, uint t) {
  return mix(((slot << frame.triangleBits) | t) + 1u, (slot << frame.swTriangleBits) | t, frame.wideIds != 0u);
}

// The raw ID (x, y as the target stores them; narrow IDs: y is 0) of a complemented payload.
uvec2 microRasterId(uint complemented) {
  uint payload = ~complemented;
  uvec2 wide = uvec2((payload >> frame.swTriangleBits) + 1u, payload & ((1u << frame.swTriangleBits) - 1u));
  return mix(uvec2(payload, 0u), wide, bvec2(frame.wideIds != 0u));
}

#endif
