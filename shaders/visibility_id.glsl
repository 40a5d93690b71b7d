// Reading the visibility target: the draw commands the IDs index and the decoding of one texel (config.h
// VIS_NOTHING, FrameData.wideIds / triangleBits). Shared by the shading pass and the material classification.
#ifndef VISBUF_VISIBILITY_ID_GLSL
#define VISBUF_VISIBILITY_ID_GLSL

#include "common.glsl"
#ifndef MSAA
#define MSAA 0
#endif

layout(std430, set = 0, binding = BINDING_DRAWS) readonly buffer DrawBlock { DrawCommand draws[]; };
layout(set = 0, binding = BINDING_DRAW_TEXELS) uniform usamplerBuffer drawTexels;  // five words per DrawCommand

// What the shading needs of draw `slot`: its LOD's first index, the mesh's vertex offset, the object (the texel
// view where VB_TEXELS: lavapipe loads a storage buffer word by word and lane by lane).
void drawAt(uint slot, out uint firstIndex, out uint vertexOffset, out uint object) {
  if (VB_TEXELS != 0u) {
    int b = int(slot * 5u);
    firstIndex = texelFetch(drawTexels, b + 2).x;
    vertexOffset = texelFetch(drawTexels, b + 3).x;
    object = texelFetch(drawTexels, b + 4).x;
    return;
  }
  firstIndex = draws[slot].firstIndex;
  vertexOffset = uint(draws[slot].vertexOffset);
  object = draws[slot].firstInstance;
}
uint drawObject(uint slot) { return VB_TEXELS != 0u ? texelFetch(drawTexels, int(slot * 5u + 4u)).x : draws[slot].firstInstance; }
#if !MSAA  // (the MSAA shading variant reads the multisampled target: msaa_samples.glsl)
layout(set = 0, binding = BINDING_VISIBILITY) uniform usampler2D visibility;
#endif

// The draw slot and the triangle in its LOD of a visibility texel; false where nothing was drawn.
bool decodeVisibility(uvec2 raw, out uint slot, out uint tri) {
  slot = 0u;
  tri = 0u;
  if (raw.x == VIS_NOTHING) return false;
  if (frame.wideIds != 0u) {
    slot = raw.x - 1u;
    tri = raw.y;
  } else {
    uint v = raw.x - 1u;
    slot = v >> frame.triangleBits;
    tri = v & ((1u << frame.triangleBits) - 1u);
  }
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
