#version 460
// Material classification, run twice over the shading tiles (one workgroup per SHADE_TILE_X x SHADE_TILE_Y tile):
//   COUNT=1: per material present in the tile, one tile and its pixel count are added to its MaterialTiles record;
//   COUNT=0 (after classify_scan gave every material its first list entry): the tile is appended to the list of
//            every material present in it.
// The materials of a tile are found by election: the lowest lane whose material is not yet handled names the next
// one, and every lane of that material is then handled; as many rounds as the tile has materials (usually 1-2),
// with no sorting and no per-material storage.
#extension GL_GOOGLE_include_directive : require
#include "visibility_id.glsl"
#include "shared/bindings_classify.h"

layout(local_size_x = SHADE_TILE_X, local_size_y = SHADE_TILE_Y) in;
layout(std430, set = 1, binding = CLASSIFY_BINDING_MATERIAL_TILES) buffer MaterialTileBlock {
  uint header[CLASSIFY_HEADER];
  MaterialTiles materialTiles[];
};
layout(std430, set = 1, binding = CLASSIFY_BINDING_TILE_LIST) writeonly buffer TileListBlock { uint tileList[]; };

const uint LANES = SHADE_TILE_X * SHADE_TILE_Y;
shared uint laneMaterial[LANES];
shared uint leader;  // lowest lane still pending this round (LANES: none left)
shared uint pixels;  // lanes of this round's material (COUNT)

void main() {
  const uint lane = gl_LocalInvocationIndex;
  const uint mine = materialAt(ivec2(gl_GlobalInvocationID.xy));
  laneMaterial[lane] = mine;
  bool pending = mine != CLASSIFY_NO_MATERIAL;
  if (lane == 0u) pixels = 0u;
  for (;;) {
    if (lane == 0u) leader = LANES;
    barrier();
    if (pending) atomicMin(leader, lane);
    barrier();
    const uint first = leader;  // the same in every lane: the loop's exit is uniform
    if (first == LANES) break;
    const uint material = laneMaterial[first];
    if (mine == material) {
      pending = false;
#if COUNT
      atomicAdd(pixels, 1u);
#endif
    }
    barrier();
    if (lane == first) {
#if COUNT
      atomicAdd(materialTiles[material].tiles, 1u);
      atomicAdd(materialTiles[material].pixels, pixels);
      pixels = 0u;  // (read and reset by the same lane, before the next round's first barrier)
#else
      uint entry = materialTiles[material].first + atomicAdd(materialTiles[material].cursor, 1u);
      tileList[entry] = gl_WorkGroupID.x | (gl_WorkGroupID.y << 16);
#endif
    }
  }
}
