#version 460
// The ID target's clear on a GPU (shade_pass recordClearIds, before the early raster, which then loads the IDs): one
// thread per pixel stores VIS_NOTHING. The raster's own LOAD_OP_CLEAR of this target ran at about 55 GB/s on the
// H100 (0.29 ms for 1080p rg32ui); a compute store is bound by bandwidth alone.
#extension GL_GOOGLE_include_directive : require
#include "shared/bindings_shade.h"
#include "shared/config.h"

layout(local_size_x = 8, local_size_y = 8) in;
#if WIDE_IDS
layout(set = 1, binding = SHADE_BINDING_IDS_STORAGE, rg32ui) uniform writeonly uimage2D ids;
#else
layout(set = 1, binding = SHADE_BINDING_IDS_STORAGE, r32ui) uniform writeonly uimage2D ids;
#endif

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, imageSize(ids)))) return;
  imageStore(ids, p, uvec4(VIS_NOTHING));
}
