#version 460
// Material classification, between the count and the scatter (classify.comp.glsl): one workgroup turns the
// per-material tile counts into first list entries (exclusive prefix sum, CLASSIFY_SCAN_WORKGROUP materials a
// step, Hillis-Steele within a step) and writes each material's indirect dispatch (rows of CLASSIFY_DISPATCH_WIDTH
// workgroups; none for a material without tiles). Also counts
// the materials present and the (tile, material) pairs.
#extension GL_GOOGLE_include_directive : require
#include "shared/types.h"
#include "shared/bindings_classify.h"
#include "uniform_branch.glsl"

layout(local_size_x = CLASSIFY_SCAN_WORKGROUP) in;
layout(push_constant) uniform Push { PassConstants pc; };  // material: the scene's material count
layout(std430, set = 1, binding = CLASSIFY_BINDING_MATERIAL_TILES) buffer MaterialTileBlock {
  uint header[CLASSIFY_HEADER];
  MaterialTiles materialTiles[];
};

shared uint sums[CLASSIFY_SCAN_WORKGROUP];
shared uint carry;    // tiles of the materials before this step
shared uint present;  // materials with pixels

void main() {
  const uint lane = gl_LocalInvocationIndex;
  if (lane == 0u) carry = present = 0u;
  barrier();
  const uint materials = uniformBranch(pc.material);
  for (uint base = 0u; base < materials; base += CLASSIFY_SCAN_WORKGROUP) {
    const uint i = base + lane;
    const uint tiles = i < materials ? materialTiles[i].tiles : 0u;
    if (tiles > 0u) atomicAdd(present, 1u);
    sums[lane] = tiles;
    barrier();
    for (uint offset = 1u; offset < CLASSIFY_SCAN_WORKGROUP; offset <<= 1) {
      const uint add = lane >= offset ? sums[lane - offset] : 0u;
      barrier();
      sums[lane] += add;
      barrier();
    }
    if (i < materials) {
      materialTiles[i].first = carry + sums[lane] - tiles;
      materialTiles[i].groupsX = min(tiles, CLASSIFY_DISPATCH_WIDTH);
      materialTiles[i].groupsY = (tiles + CLASSIFY_DISPATCH_WIDTH - 1u) / CLASSIFY_DISPATCH_WIDTH;
      materialTiles[i].groupsZ = 1u;
    }
    barrier();
    if (lane == CLASSIFY_SCAN_WORKGROUP - 1u) carry += sums[lane];
    barrier();
  }
  if (lane == 0u) {
    header[CLASSIFY_STAT_PAIRS] = carry;
    header[CLASSIFY_STAT_MATERIALS] = present;
  }
}
