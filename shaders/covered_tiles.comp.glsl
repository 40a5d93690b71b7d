#version 460
// Covered-tile list (shade_pass, the ubershader's covered-tile dispatch): one thread per 8x8 shading tile reads
// its IDs and appends the tile when any pixel shows something (one atomic per subgroup); then (pc.variant 1, one
// thread) the shading dispatch's VkDispatchIndirectCommand: the tiles in rows of CLASSIFY_DISPATCH_WIDTH. The
// shading pass then runs one workgroup per covered tile instead of one per tile of the frame: the background
// (cleared before) costs nothing.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "visibility_id.glsl"

layout(local_size_x = COVERED_TILES_WORKGROUP) in;
layout(push_constant) uniform Push { PassConstants pc; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer CoveredTiles { uint words[]; };

void main() {
  CoveredTiles list = CoveredTiles(uvec2(frame.coveredTilesLow, frame.coveredTilesHigh));
  if (pc.variant == 1u) {  // the indirect dispatch, once every tile is listed
    if (gl_GlobalInvocationID.x != 0u) return;
    uint count = list.words[3];
    list.words[0] = min(count, CLASSIFY_DISPATCH_WIDTH);
    list.words[1] = (count + CLASSIFY_DISPATCH_WIDTH - 1u) / CLASSIFY_DISPATCH_WIDTH;
    list.words[2] = 1u;
    return;
  }
  uint tilesX = frame.coveredTilesX;
  uint tilesY = (uint(frame.viewport.y) + SHADE_TILE_Y - 1u) / SHADE_TILE_Y;
  uint tile = gl_GlobalInvocationID.x;
  bool covered = false;
  if (tile < tilesX * tilesY) {
    ivec2 origin = ivec2(tile % tilesX, tile / tilesX) * ivec2(SHADE_TILE_X, SHADE_TILE_Y);
    ivec2 size = min(ivec2(SHADE_TILE_X, SHADE_TILE_Y), ivec2(frame.viewport.xy) - origin);
    for (int y = 0; y < size.y && !covered; ++y)
      for (int x = 0; x < size.x && !covered; ++x)
        covered = texelFetch(visibility, origin + ivec2(x, y), 0).x != VIS_NOTHING;
  }
  uvec4 ballot = subgroupBallot(covered);
  uint n = subgroupBallotBitCount(ballot);
  uint first = 0u;
  if (subgroupElect() && n > 0u) first = atomicAdd(list.words[3], n);
  first = subgroupBroadcastFirst(first);
  if (covered)
    list.words[COVERED_TILES_HEADER + first + subgroupBallotExclusiveBitCount(ballot)] =
        (tile % tilesX) | (tile / tilesX) << 16;
}
