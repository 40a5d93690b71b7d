#version 460
// Copies every sample of the multisampled ID target into a buffer (vkCmdCopyImageToBuffer cannot read
// multisampled images): (pixel * samples + sample) * 2 + {0, 1} = the sample's raw (x, y) texel, y = 0 for r32ui.
// For FrameOptions::readIds of MSAA frames (tests, the ID views); the attribute buffer holds the copy.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "shared/bindings_shade.h"

layout(local_size_x = SHADE_TILE_X, local_size_y = SHADE_TILE_Y) in;
layout(set = 1, binding = SHADE_BINDING_VISIBILITY) uniform usampler2DMS visibility;
layout(std430, set = 1, binding = SHADE_BINDING_ATTRIBUTES) writeonly buffer SampleIdBlock { uint sampleIds[]; };

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= int(frame.viewport.x) || p.y >= int(frame.viewport.y)) return;
  uint base = (uint(p.y) * uint(frame.viewport.x) + uint(p.x)) * frame.msaaSamples;
  for (uint s = 0u; s < frame.msaaSamples; ++s) {
    uvec2 raw = texelFetch(visibility, p, int(s)).xy;
    sampleIds[2u * (base + s)] = raw.x;
    sampleIds[2u * (base + s) + 1u] = raw.y;
  }
}
