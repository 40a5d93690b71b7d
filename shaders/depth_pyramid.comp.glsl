#version 460
// Depth pyramid pass: a conservative reduction of the visibility depth. Reverse-Z, so each texel keeps
// the FARTHEST depth (the minimum) of the texels it covers. Level k texel (x, y) covers exactly the
// full-resolution pixels [x 2^k, (x+1) 2^k) x [y 2^k, (y+1) 2^k) clipped to the image, at any size
// (odd and non-power-of-two included): level k is built from the <= 2x2 valid texels of level k-1
// (sizes ceil(size / 2^k)); no sampler filtering is involved (no samplerFilterMinmax dependency).
#extension GL_GOOGLE_include_directive : require
#include "shared/types.h"

layout(local_size_x = PYRAMID_TILE, local_size_y = PYRAMID_TILE) in;
#if MSAA
// Level 0 of a multisampled depth: each texel is the farthest (minimum) depth over the pixel's samples, so every
// sample's depth is nearer than or equal to it (conservative for the occlusion test at any sample).
layout(set = 0, binding = 0) uniform sampler2DMS source;
#else
layout(set = 0, binding = 0) uniform sampler2D source;  // level 0: the depth image; else level k-1
#endif
layout(set = 0, binding = 1, r32f) uniform writeonly image2D destination;
layout(push_constant) uniform Push { PyramidConstants pc; };

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= int(pc.dstWidth) || p.y >= int(pc.dstHeight)) return;
  const ivec2 srcSize = ivec2(pc.srcWidth, pc.srcHeight);
  float d;
#if MSAA
  d = texelFetch(source, p, 0).r;
  for (int i = 1; i < textureSamples(source); ++i) d = min(d, texelFetch(source, p, i).r);
#else
  if (pc.level == 0u) {
    d = texelFetch(source, p, 0).r;
  } else {
    ivec2 s = p * 2;
    d = texelFetch(source, s, 0).r;
    if (s.x + 1 < srcSize.x) d = min(d, texelFetch(source, s + ivec2(1, 0), 0).r);
    if (s.y + 1 < srcSize.y) d = min(d, texelFetch(source, s + ivec2(0, 1), 0).r);
    if (s.x + 1 < srcSize.x && s.y + 1 < srcSize.y) d = min(d, texelFetch(source, s + ivec2(1, 1), 0).r);
  }
#endif
  imageStore(destination, p, vec4(d));
}
