// Reading the visibility target: the draw commands the IDs index and the decoding of one texel (config.h
// VIS_NOTHING, FrameData.wideIds / triangleBits). Shared by the shading pass and the material classification.
#ifndef VISBUF_VISIBILITY_ID_GLSL
#define VISBUF_VISIBILITY_ID_GLSL

#include "sw_payload.glsl"
#include "shared/bindings_shade.h"
#ifndef MSAA
#define MSAA 0
#endif
#ifndef SW_RESOLVE  // 1: the variants of frames whose micro-raster was not merged (FramePlan::swResolved)
#define SW_RESOLVE 0
#endif

layout(std430, set = 1, binding = SHADE_BINDING_DRAWS) readonly buffer DrawBlock { DrawCommand draws[]; };
layout(set = 1, binding = SHADE_BINDING_DRAW_TEXELS) uniform usamplerBuffer drawTexels;  // five words per DrawCommand

// The object of draw `slot` (its firstInstance), and what the shading needs of it: its LOD's first index and the
// mesh's vertex offset. Through the texel view where VB_TEXELS (lavapipe loads a storage buffer word by word and
// lane by lane).
uint drawObject(uint slot) {
  if (VB_TEXELS != 0u) return texelFetch(drawTexels, int(slot * 5u + 4u)).x;
  return draws[slot].firstInstance;
}
void drawAt(uint slot, out uint firstIndex, out uint vertexOffset, out uint object) {
  object = drawObject(slot);
  if (VB_TEXELS != 0u) {
    firstIndex = texelFetch(drawTexels, int(slot * 5u + 2u)).x;
    vertexOffset = texelFetch(drawTexels, int(slot * 5u + 3u)).x;
    return;
  }
  firstIndex = draws[slot].firstIndex;
  vertexOffset = uint(draws[slot].vertexOffset);
}
#if !MSAA  // (the MSAA shading variant reads the multisampled target: msaa_samples.glsl)
layout(set = 1, binding = SHADE_BINDING_VISIBILITY) uniform usampler2D visibility;
#endif
#if !MSAA && SW_RESOLVE
layout(set = 1, binding = SHADE_BINDING_DEPTH) uniform sampler2D visibilityDepth;

// The micro-raster's buffer as (low, high) word pairs: high, the depth bits (0: nothing); low, the complemented
// payload (equal depths keep the lowest payload). Through its RG32UI texel view: on lavapipe one vector load for the
// batch, where a storage-buffer read is a bounds-checked scalar load per lane and word.
layout(set = 1, binding = SHADE_BINDING_SW_TEXELS) uniform usamplerBuffer swTexels;
uvec2 microRasterWord(ivec2 p) { return texelFetch(swTexels, p.y * int(frame.viewport.x) + p.x).xy; }
uint microRasterDepthBits(ivec2 p) { return microRasterWord(p).y; }

// Whether the micro-raster's fragment (depth bits, 0: none) is nearer than the raster's at p (drawn: the raster drew
// p): the rule of the merge this replaces (sw_merge.frag, depth test GREATER, reverse-Z), so the raster's fragment
// keeps an equal depth. Reads the depth only where both drew.
bool microRasterNearer(ivec2 p, uint depthBits, bool drawn) {
  if (depthBits == 0u) return false;
  return !drawn || uintBitsToFloat(depthBits) > texelFetch(visibilityDepth, p, 0).r;
}

// The raw ID at p given the target's raw ID there: the micro-raster's where its fragment is nearer.
uvec2 resolveMicroRaster(ivec2 p, uvec2 raw) {
  uvec2 sw = microRasterWord(p);
  return microRasterNearer(p, sw.y, raw.x != VIS_NOTHING) ? microRasterId(sw.x) : raw;
}
// The raw ID at p: the target's, or where the micro-raster's fragment is nearer, the micro-raster's.
uvec2 resolvedVisibility(ivec2 p) { return resolveMicroRaster(p, texelFetch(visibility, p, 0).xy); }
#endif

// The draw slot and the triangle in its LOD of a visibility texel; false where nothing was drawn.
bool decodeVisibility(uvec2 raw, out uint slot, out uint tri) {
  slot = 0u;
  tri = 0u;
  if (raw.x == VIS_NOTHING) return false;
  uint v = raw.x - 1u;  // (selects, not a branch: uniform_branch.glsl says why)
  bool wide = frame.wideIds != 0u;
  slot = mix(v >> frame.triangleBits, v, wide);
  tri = mix(v & ((1u << frame.triangleBits) - 1u), raw.y, wide);
  return true;
}

#if !MSAA
// The material drawn at pixel p (CLASSIFY_NO_MATERIAL: nothing, or outside the frame).
uint materialAt(ivec2 p) {
  uint slot, tri;
  if (p.x >= int(frame.viewport.x) || p.y >= int(frame.viewport.y) ||
      !decodeVisibility(texelFetch(visibility, p, 0).xy, slot, tri))
    return CLASSIFY_NO_MATERIAL;
  return objectAt(drawObject(slot)).materialIndex;
}
#endif

#endif
