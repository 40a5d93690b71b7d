// The cull passes' shared part (cull.comp.glsl, cull_clusters.comp.glsl): set 1's bindings (bindings_cull.h) and the
// tests both apply to a bounding sphere -- frustum, screen rectangle, micro-raster size, depth pyramid.
#ifndef VISBUF_CULL_TESTS_GLSL
#define VISBUF_CULL_TESTS_GLSL
#include "common.glsl"
#include "shared/bindings_cull.h"

layout(local_size_x = CULL_WORKGROUP_SIZE) in;
layout(std430, set = 1, binding = CULL_BINDING_DRAWS) writeonly buffer DrawBlock { DrawCommand draws[]; };
layout(std430, set = 0, binding = SCENE_BINDING_STATS) buffer StatBlock { uint stats[]; };
layout(std430, set = 1, binding = CULL_BINDING_HISTORY) buffer HistoryBlock { uint history[]; };
layout(std430, set = 1, binding = CULL_BINDING_VISIBLE_LIST) buffer VisibleListBlock { uint visibleList[]; };
layout(std430, set = 1, binding = CULL_BINDING_DRAW_LISTS) readonly buffer DrawListBlock { uvec4 drawLists[]; };
layout(set = 1, binding = CULL_BINDING_PYRAMID) uniform sampler2D pyramid;
layout(std430, set = 1, binding = CULL_BINDING_CLUSTERS) readonly buffer ClusterBlock { ClusterData clusters[]; };
layout(push_constant) uniform Push { PassConstants pc; };

// Appends the IDs of the lanes where `mine` holds to the list at word `base` of the visible-list buffer (count, indirect
// dispatch size, then IDs): one atomic per subgroup for the slots, one for the dispatch size.
void appendToList(uint base, bool mine, uint id) {
  uvec4 ballot = subgroupBallot(mine);
  uint count = subgroupBallotBitCount(ballot);
  if (count == 0u) return;
  uint first = 0u;
  if (subgroupElect()) {
    first = atomicAdd(visibleList[base], count);
    atomicMax(visibleList[base + 1u], (first + count + CULL_WORKGROUP_SIZE - 1u) / CULL_WORKGROUP_SIZE);
  }
  first = subgroupBroadcastFirst(first);
  if (mine) visibleList[base + VISIBLE_LIST_HEADER + first + subgroupBallotExclusiveBitCount(ballot)] = id;
}

// Draw slots for the lanes where `pending` holds, each in the region of its `key` (hardware draws of list l: l;
// micro-raster draws: DRAW_LISTS + l) in this phase: one atomic per subgroup and key present (a scene with one list
// loops once), the draws counted in stats[counter] too; where the micro-raster takes one, its dispatch (it
// grid-strides) and merge run this phase. Returns the lane's slot among its key's draws of the phase.
uint takeDrawSlots(bool pending, uint key, uint phase, uint counter) {
  uint slot = 0u;
  while (subgroupAny(pending)) {
    uint current = subgroupMin(pending ? key : DRAW_LIST_NONE);
    bool mine = pending && key == current;
    uvec4 ballot = subgroupBallot(mine);
    uint count = subgroupBallotBitCount(ballot);
    uint base = 0u;
    if (subgroupElect()) {
      atomicAdd(stats[counter], count);
      uint listCounter = current < DRAW_LISTS ? STAT_LIST_DRAWS + phase * DRAW_LISTS + current
                                              : STAT_SW_DRAWS + phase * DRAW_LISTS + current - DRAW_LISTS;
      base = atomicAdd(stats[listCounter], count);
      if (current >= DRAW_LISTS) {
        uint args = SW_ARGS + phase * SW_ARGS_UINTS;
        atomicMax(stats[args + SW_ARGS_DISPATCH], min((base + count + 7u) / 8u, SW_RASTER_MAX_WORKGROUPS));
        atomicMax(stats[args + SW_ARGS_MERGE], 3u);
      }
    }
    base = subgroupBroadcastFirst(base);
    if (mine) slot = base + subgroupBallotExclusiveBitCount(ballot);
    pending = pending && !mine;
  }
  return slot;
}

// Whether this phase's surviving clusters of draw list `list` may go to the micro-raster (the small ones). Where the
// phase's cluster reservations in the list ran out, which objects were drawn whole depends on the order the GPU ran
// them: their clusters then stay with the hardware raster too, so that the image does not depend on it (the
// micro-raster may break an edge tie otherwise than the hardware raster).
bool clustersMayUseMicroRaster(uint phase, uint list) {
  bool exhausted = stats[STAT_CLUSTER_RESERVED + phase * DRAW_LISTS + list] > drawLists[DRAW_LISTS + list].x;
  return !exhausted && frame.swRaster != 0u && drawLists[list].w != 0u && CLUSTER_TRIANGLES <= frame.swMaxTriangles;
}

bool frustumVisible(vec3 c, float r) {
  // Conservative margin: covers float rounding of the plane distance (a few ulps of the magnitudes
  // involved), so the GPU never culls what a double-precision test keeps.
  float margin = 1e-5 * (abs(c.x) + abs(c.y) + abs(c.z) + r) + 1e-6;
  bool visible = true;
  for (int i = 0; i < 5; ++i)
    if (dot(frame.frustum[i].xyz, c) + frame.frustum[i].w < -(r + margin)) visible = false;
  if (dot(frame.farPlane.xyz, c) + frame.farPlane.w < -(r + margin)) visible = false;  // (infinite: never)
  return visible;
}

// Screen rectangle (NDC) of the sphere's bounding cube; false if the sphere touches the near plane or a finite far
// plane. v: the centre in view space, rr: the radius widened for rounding. Every corner is then in front of the
// camera, so the hull of the projected corners contains the projected sphere. Perspective: the corners have two
// depths and two x (y) values: the hull's bounds are among their four quotients each (two reciprocals instead of
// eight divisions; the occlusion test's 0.01-pixel margin covers the ulp this rounds differently). Orthographic: the
// cube's x (y) extent scaled, whatever its depth.
bool screenRect(vec3 c, float r, out vec3 v, out float rr, out vec2 lo, out vec2 hi) {
  v = (frame.view * vec4(c, 0.0)).xyz;  // view space, camera looks down -z
  rr = r * (1.0 + 1e-5) + 1e-6;
  lo = vec2(1e30);
  hi = vec2(-1e30);
  if (-(v.z + rr) <= frame.nearPlane * 1.001) return false;
  if (frame.projection.w > 0.0 && -(v.z - rr) >= frame.projection.w * 0.999) return false;
  vec2 proj = vec2(frame.projX, frame.projY);
  vec2 a = proj * (v.xy - rr), b = proj * (v.xy + rr);
  if (orthographic()) {
    lo = min(a, b);
    hi = max(a, b);
    return true;
  }
  float nearInv = 1.0 / -(v.z + rr), farInv = 1.0 / -(v.z - rr);
  lo = min(min(a * nearInv, a * farInv), min(b * nearInv, b * farInv));
  hi = max(max(a * nearInv, a * farInv), max(b * nearInv, b * farInv));
  return true;
}

// Software micro-raster routing: the object's screen box (rect: screenRect's) is at most frame.swMaxPixels per
// side, its triangles are small (FrameData.swMaxAreaPerTriangle) and it lies wholly beyond the near plane
// (sw_raster.comp needs no clipping and keeps its edge functions within 32 bits).
bool smallOnScreen(bool rect, vec2 lo, vec2 hi, uint triangles) {
  vec2 extent = (hi - lo) * 0.5 * frame.viewport.xy;
  return rect && max(extent.x, extent.y) <= frame.swMaxPixels &&
         extent.x * extent.y <= frame.swMaxAreaPerTriangle * float(triangles);
}

// The farthest depth the pyramid holds over the pixels [a, b] (reverse-Z: the minimum of the level's texels over
// them; every level is a conservative reduction of the ones below).
float farthestDepth(ivec2 a, ivec2 b, int level) {
  ivec2 ta = a >> level, tb = b >> level;
  float farthest = 1.0;
  for (int y = ta.y; y <= tb.y; ++y)
    for (int x = ta.x; x <= tb.x; ++x) farthest = min(farthest, texelFetch(pyramid, ivec2(x, y), level).r);
  return farthest;
}

// farthestDepth where [a, b] spans at most 2x2 texels of the level: four fetches, no loop (lavapipe runs a loop with
// per-lane bounds as often as its longest lane needs, and keeps a mask per pass).
float farthestDepth2x2(ivec2 a, ivec2 b, int level) {
  ivec2 ta = a >> level, tb = b >> level;
  return min(min(texelFetch(pyramid, ta, level).r, texelFetch(pyramid, ivec2(tb.x, ta.y), level).r),
             min(texelFetch(pyramid, ivec2(ta.x, tb.y), level).r, texelFetch(pyramid, tb, level).r));
}

// 0: visible, 1: occluded by the pyramid, 2: covers no pixel centre, 4: not proved occluded at the coarse level
// where a finer one exists (to the refinement list; `refine`: the refinement dispatch's test, 0 or 1). rect, v,
// rr, lo, hi: screenRect's.
uint occlusionTest(bool rect, vec3 v, float rr, vec2 lo, vec2 hi, bool refine, bool usePyramid) {
  if (!rect) return 0u;  // touches the near plane: always visible
  vec2 size = frame.viewport.xy;
  // Pixel centres (p + 0.5) inside [lo, hi] in pixels, widened by a small tolerance for rounding. MSAA: a
  // triangle can cover a sample and no centre; every sample lies within 0.5 px of its pixel's centre (per axis),
  // so widening by 0.5 keeps every pixel with a covered sample (and the pyramid texels over it).
  float margin = frame.msaaSamples > 1u ? 0.51 : 0.01;
  vec2 pxLo = (lo * 0.5 + 0.5) * size - 0.5 - margin;
  vec2 pxHi = (hi * 0.5 + 0.5) * size - 0.5 + margin;
  ivec2 a = ivec2(ceil(pxLo));
  ivec2 b = ivec2(floor(pxHi));
  a = max(a, ivec2(0));
  b = min(b, ivec2(size) - 1);
  if (a.x > b.x || a.y > b.y) return 2u;  // no pixel centre can be covered
  if (!usePyramid || frame.pyramidLevels == 0u) return 0u;  // (pyramid skipped this frame: it occluded nothing lately)
  // Level whose texels span the rectangle in at most 2x2 texels: 2^k >= extent (never floor(log2)).
  int extent = max(b.x - a.x + 1, b.y - a.y + 1);
  // (Never below PYRAMID_FIRST_TESTED_LEVEL: the frame does not build level 0.)
  int top = int(frame.pyramidLevels) - 1;
  int level = min(max(int(ceil(log2(float(extent)))), PYRAMID_FIRST_TESTED_LEVEL), top);
  if ((1 << level) < extent) level = min(level + 1, top);  // guard log2 rounding
  // The object's nearest possible depth, rounded towards nearer (the depth's rounding is relative for perspective;
  // an orthographic depth is linear in [0, 1], so its rounding is absolute).
  float nearest = depthOfDistance(-(v.z + rr)) * (1.0 + 1e-5) + (orthographic() ? 1e-6 : 1e-6 * frame.projection.x);
  // That level's texels may reach past the rectangle by up to their own size per axis (up to 4x its area): what it
  // does not prove occluded is tested again three levels finer, in at most 9x9 texels that reach past it by at most
  // 1/4 of its extent per axis. The peer field (1M kittens): 61,487 objects drawn with the coarse level alone,
  // 45,049 two levels finer, 41,297 three levels finer, 38,110 at full resolution. That runs in the refinement
  // dispatch, dense over the few objects concerned (on lavapipe a loop here would run in every SIMD batch that
  // holds one of them).
  int fine = min(max(level - 3, PYRAMID_FIRST_TESTED_LEVEL), top);
  if (refine) return nearest < farthestDepth(a, b, fine) ? 1u : 0u;
  bool spans2x2 = all(lessThanEqual((b >> level) - (a >> level), ivec2(1)));  // (not where the top level capped it)
  if (nearest < (spans2x2 ? farthestDepth2x2(a, b, level) : farthestDepth(a, b, level))) return 1u;
  return fine < level ? 4u : 0u;
}

#endif
