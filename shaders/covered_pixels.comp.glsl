#version 460
// Covered-pixel list (shade_pass, the ubershader's covered-pixel dispatch): one thread per 8x8 shading tile counts
// the tile's pixels that show something, takes that many entries (one atomic per subgroup) and lists them
// (x | y << 16, row by row; the SW_RESOLVE variant sets COVERED_PIXEL_MICRO_RASTER where the unmerged micro-raster
// drew, and the shading decides which of its and the raster's fragments is nearer: the depth is read per covered
// pixel there, not per pixel of the frame here); then (pc.variant 1, one thread) the shading dispatch's
// VkDispatchIndirectCommand: one workgroup per SHADE_TILE_X x SHADE_TILE_Y listed pixels, in rows of
// CLASSIFY_DISPATCH_WIDTH. The shading pass then
// runs one thread per covered pixel: the background (cleared before) costs nothing, and no lane shades a background
// pixel of a covered tile (lavapipe runs every lane of a batch through the whole shading code, masked or not).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "uniform_branch.glsl"
#include "visibility_id.glsl"

layout(local_size_x = COVERED_TILES_WORKGROUP) in;
layout(push_constant) uniform Push { PassConstants pc; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer CoveredPixels { uint words[]; };
layout(std430, set = 0, binding = SCENE_BINDING_STATS) buffer StatsBlock { uint stats[]; };  // STAT_COVERED_PIXELS

void main() {
  CoveredPixels list = CoveredPixels(uvec2(frame.coveredPixelsLow, frame.coveredPixelsHigh));
  if (uniformBranch(pc.variant) == 1u) {  // the indirect dispatch, once every pixel is listed
    if (gl_GlobalInvocationID.x != 0u) return;
    uint groups = (list.words[3] + SHADE_TILE_X * SHADE_TILE_Y - 1u) / (SHADE_TILE_X * SHADE_TILE_Y);
    list.words[0] = min(groups, CLASSIFY_DISPATCH_WIDTH);
    list.words[1] = (groups + CLASSIFY_DISPATCH_WIDTH - 1u) / CLASSIFY_DISPATCH_WIDTH;
    list.words[2] = 1u;
    // The pixels the shading will shade: every listed one (it counts none itself; on lavapipe its atomic per
    // subgroup was a locked add bouncing between the cores, once per eight pixels).
    stats[STAT_COVERED_PIXELS] = list.words[3];
    return;
  }
  uint tilesX = frame.coveredTilesX;
  uint tilesY = (uint(frame.viewport.y) + SHADE_TILE_Y - 1u) / SHADE_TILE_Y;
  uint tile = gl_GlobalInvocationID.x;
  ivec2 origin = ivec2(0), size = ivec2(0);
  if (tile < tilesX * tilesY) {
    origin = ivec2(tile % tilesX, tile / tilesX) * ivec2(SHADE_TILE_X, SHADE_TILE_Y);
    size = min(ivec2(SHADE_TILE_X, SHADE_TILE_Y), ivec2(frame.viewport.xy) - origin);
  }
#if SW_RESOLVE
  // The tile's pixels that show something, and those of them where the micro-raster drew, as 64-bit masks in two
  // words (bit y * SHADE_TILE_X + x).
  uvec2 shown = uvec2(0u), micro = uvec2(0u);
  for (int y = 0; y < size.y; ++y)
    for (int x = 0; x < size.x; ++x) {
      ivec2 p = origin + ivec2(x, y);
      uint bit = uint(y * SHADE_TILE_X + x), word = bit >> 5u, mask = 1u << (bit & 31u);
      bool drawn = texelFetch(visibility, p, 0).x != VIS_NOTHING;
      if (microRasterDepthBits(p) != 0u) micro[word] |= mask;
      if (drawn) shown[word] |= mask;
    }
  shown |= micro;
  uint count = bitCount(shown.x) + bitCount(shown.y);
#else
  uint count = 0u;
  for (int y = 0; y < size.y; ++y)
    for (int x = 0; x < size.x; ++x) count += texelFetch(visibility, origin + ivec2(x, y), 0).x != VIS_NOTHING ? 1u : 0u;
#endif
  uint total = subgroupAdd(count), at = subgroupExclusiveAdd(count);
  uint first = 0u;
  if (subgroupElect() && total > 0u) first = atomicAdd(list.words[3], total);
  at += subgroupBroadcastFirst(first) + COVERED_PIXELS_HEADER;
#if SW_RESOLVE
  for (uint word = 0u; word < 2u; ++word)
    for (uint bits = shown[word]; bits != 0u; bits &= bits - 1u) {
      uint bit = uint(findLSB(bits)), i = word * 32u + bit;
      ivec2 p = origin + ivec2(i % uint(SHADE_TILE_X), i / uint(SHADE_TILE_X));
      list.words[at++] = uint(p.x) | uint(p.y) << 16 | ((micro[word] >> bit) & 1u) * COVERED_PIXEL_MICRO_RASTER;
    }
#else
  for (int y = 0; y < size.y && count > 0u; ++y)
    for (int x = 0; x < size.x; ++x) {
      ivec2 p = origin + ivec2(x, y);
      if (texelFetch(visibility, p, 0).x != VIS_NOTHING) list.words[at++] = uint(p.x) | uint(p.y) << 16;
    }
#endif
}
