// The micro-raster's payload (sw_raster.comp), stored complemented beside its depth bits, and the raw ID of the
// visibility target's encoding it stands for (FrameData.wideIds / triangleBits / swTriangleBits): written by the
// merge (sw_merge.frag) and by the resolve (visibility_id.glsl) in the one way this file gives.
#ifndef VISBUF_SW_PAYLOAD_GLSL
#define VISBUF_SW_PAYLOAD_GLSL

#include "common.glsl"

// Triangle t of draw `slot`. Lower payloads are earlier in draw order (lower slot, then lower triangle).
uint microRasterPayload(uint slot, uint t) {
  return frame.wideIds != 0u ? (slot << frame.swTriangleBits) | t : ((slot << frame.triangleBits) | t) + 1u;
}

// The raw ID (x, y as the target stores them; narrow IDs: y is 0) of a complemented payload.
uvec2 microRasterId(uint complemented) {
  uint payload = ~complemented;
  if (frame.wideIds == 0u) return uvec2(payload, 0u);
  return uvec2((payload >> frame.swTriangleBits) + 1u, payload & ((1u << frame.swTriangleBits) - 1u));
}

#endif
