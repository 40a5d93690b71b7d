#version 460
// Depth pyramid pass: a conservative reduction of the visibility depth. Reverse-Z, so each texel keeps
// the FARTHEST depth (the minimum) of the texels it covers. Level k texel (x, y) covers exactly the
// full-resolution pixels [x 2^k, (x+1) 2^k) x [y 2^k, (y+1) 2^k) clipped to the image, at any size
// (odd and non-power-of-two included): level k is the minimum of the <= 2x2 valid texels of level k-1
// (sizes ceil(size / 2^k)); no sampler filtering is involved (no samplerFilterMinmax dependency).
//
// One dispatch builds up to PYRAMID_REDUCTIONS levels: each thread reduces an 8x8 block of the dispatch's source
// level to 4x4, 2x2 and 1 texel by itself (no shared memory, no barrier: on lavapipe a workgroup barrier costs more
// than the reduction). The first dispatch reads the depth image; where level 0 is read back it also writes it (a
// copy, or for MSAA the farthest of each pixel's samples), since the occlusion tests never read it
// (PYRAMID_FIRST_TESTED_LEVEL). Each later dispatch reads the last level written. 1024x768 takes four dispatches
// (levels 0-3, 4-6, 7-9, 10) instead of eleven.
#extension GL_GOOGLE_include_directive : require
#include "shared/types.h"

layout(local_size_x = PYRAMID_TILE, local_size_y = PYRAMID_TILE) in;
#if MSAA
// Level 0 of a multisampled depth: each texel is the farthest (minimum) depth over the pixel's samples, so every
// sample's depth is nearer than or equal to it (conservative for the occlusion test at any sample).
layout(set = 0, binding = 0) uniform sampler2DMS source;
#else
layout(set = 0, binding = 0) uniform sampler2D source;  // the depth image, or the last level of the dispatch before
#endif
// Slot j: the level source + j (slot 0, the source's own level, is written only by the copying dispatch).
layout(set = 0, binding = 1, r32f) uniform writeonly image2D levels[PYRAMID_DISPATCH_LEVELS];
layout(push_constant) uniform Push { PyramidConstants pc; };
#if !MSAA
// The micro-raster's 64-bit words as RG32UI texels: y, the depth bits (passes::SwRasterPass::texels).
layout(set = 0, binding = 2) uniform usamplerBuffer microRaster;
#endif

const int BLOCK = 1 << PYRAMID_REDUCTIONS;

// Beyond the valid size a texel takes 1.0, which no depth is nearer than: the minimum is then the clipped one.
float sourceDepth(ivec2 s) {
  if (s.x >= int(pc.srcWidth) || s.y >= int(pc.srcHeight)) return 1.0;
#if MSAA
  float d = texelFetch(source, s, 0).r;
  for (int i = 1; i < textureSamples(source); ++i) d = min(d, texelFetch(source, s, i).r);
  return d;
#else
  float d = texelFetch(source, s, 0).r;
  if (pc.swResolve != 0u)  // the micro-raster's fragment, not merged into the depth: the nearer of the two
    d = max(d, uintBitsToFloat(texelFetch(microRaster, s.y * int(pc.srcWidth) + s.x).y));
  return d;
#endif
}

void main() {
  ivec2 origin = ivec2(gl_GlobalInvocationID.xy) * BLOCK;  // this thread's block of the source level
  ivec2 size = ivec2(pc.srcWidth, pc.srcHeight);
  bool copy = pc.copySource != 0u;
  // Level source + 1: 4x4 texels, each the minimum of 2x2 source texels.
  float l1[BLOCK / 2][BLOCK / 2];
  ivec2 size1 = (size + 1) / 2;
  for (int y = 0; y < BLOCK / 2; ++y)
    for (int x = 0; x < BLOCK / 2; ++x) {
      ivec2 s = origin + 2 * ivec2(x, y);
      float d00 = sourceDepth(s), d10 = sourceDepth(s + ivec2(1, 0));
      float d01 = sourceDepth(s + ivec2(0, 1)), d11 = sourceDepth(s + ivec2(1, 1));
      if (copy) {
        if (s.x < size.x && s.y < size.y) imageStore(levels[0], s, vec4(d00));
        if (s.x + 1 < size.x && s.y < size.y) imageStore(levels[0], s + ivec2(1, 0), vec4(d10));
        if (s.x < size.x && s.y + 1 < size.y) imageStore(levels[0], s + ivec2(0, 1), vec4(d01));
        if (s.x + 1 < size.x && s.y + 1 < size.y) imageStore(levels[0], s + ivec2(1, 1), vec4(d11));
      }
      l1[y][x] = min(min(d00, d10), min(d01, d11));
      ivec2 t = origin / 2 + ivec2(x, y);
      if (pc.reductions >= 1u && t.x < size1.x && t.y < size1.y) imageStore(levels[1], t, vec4(l1[y][x]));
    }
  if (pc.reductions < 2u) return;
  // Level source + 2: 2x2 texels.
  ivec2 size2 = (size1 + 1) / 2;
  float l2[2][2];
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) {
      l2[y][x] = min(min(l1[2 * y][2 * x], l1[2 * y][2 * x + 1]), min(l1[2 * y + 1][2 * x], l1[2 * y + 1][2 * x + 1]));
      ivec2 t = origin / 4 + ivec2(x, y);
      if (t.x < size2.x && t.y < size2.y) imageStore(levels[2], t, vec4(l2[y][x]));
    }
  if (pc.reductions < 3u) return;
  // Level source + 3: one texel.
  ivec2 size3 = (size2 + 1) / 2;
  ivec2 t = origin / 8;
  if (t.x < size3.x && t.y < size3.y)
    imageStore(levels[3], t, vec4(min(min(l2[0][0], l2[0][1]), min(l2[1][0], l2[1][1]))));
}
