#version 460
// Cull pass: one thread per object. Bounding sphere vs the camera-relative frustum planes, LOD by
// projected error, then append a VkDrawIndexedIndirectCommand (firstInstance = object ID). Slots are
// allocated with one atomic per subgroup (ballot + prefix count).
//
// Occlusion mode runs this twice per frame (Hill & Collin's two-phase scheme as used by niagara):
//   early: objects visible at the end of last frame (history, dispatched over its list) -> frustum + LOD -> drawn
//          first;
//   late:  every object -> frustum -> sub-pixel and depth-pyramid tests (pyramid of the early depth)
//          -> drawn if visible and not already drawn early; history := visible.
//          The pyramid test runs at the level whose texels span the object's rectangle in 2x2; the objects it does
//          not prove occluded are listed and tested again, three levels finer, by a second dispatch over that list
//          (CULL_REFINE), which decides them as above.
// The early depth is a subset of the final depth, so the late test never hides a visible object,
// whatever the history holds: a stale or cleared history only costs time.
// Clusters (FrameData.clusterCull): an object it would draw whole with the hardware raster, whose LOD has clusters,
// is listed instead (object, LOD), and the phase's cluster dispatch (CULL_CLUSTERS, one workgroup per listed
// object) tests each cluster against the frustum, its back-face cone and, late, the pyramid; a small surviving
// cluster goes to the micro-raster, the others are drawn as one draw per run of consecutive survivors.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
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

bool frustumVisible(vec3 c, float r) {
  // Conservative margin: covers float rounding of the plane distance (a few ulps of the magnitudes
  // involved), so the GPU never culls what a double-precision test keeps.
  float margin = 1e-5 * (abs(c.x) + abs(c.y) + abs(c.z) + r) + 1e-6;
  bool visible = true;
  for (int i = 0; i < 5; ++i)
    if (dot(frame.frustum[i].xyz, c) + frame.frustum[i].w < -(r + margin)) visible = false;
  return visible;
}

// Screen rectangle (NDC) of the sphere's bounding cube; false if the sphere touches the near plane. v: the centre in
// view space, rr: the radius widened for rounding. Every corner is then in front of the camera, so the hull of the
// projected corners contains the projected sphere. The corners have two depths and two x (y) values: the hull's
// bounds are among their four quotients each (two reciprocals instead of eight divisions; the occlusion test's
// 0.01-pixel margin covers the ulp this rounds differently).
bool screenRect(vec3 c, float r, out vec3 v, out float rr, out vec2 lo, out vec2 hi) {
  v = (frame.view * vec4(c, 0.0)).xyz;  // view space, camera looks down -z
  rr = r * (1.0 + 1e-5) + 1e-6;
  lo = vec2(1e30);
  hi = vec2(-1e30);
  if (-(v.z + rr) <= frame.nearPlane * 1.001) return false;
  float nearInv = 1.0 / -(v.z + rr), farInv = 1.0 / -(v.z - rr);
  vec2 proj = vec2(frame.projX, frame.projY);
  vec2 a = proj * (v.xy - rr), b = proj * (v.xy + rr);
  lo = min(min(a * nearInv, a * farInv), min(b * nearInv, b * farInv));
  hi = max(max(a * nearInv, a * farInv), max(b * nearInv, b * farInv));
  return true;
}

// Software micro-raster routing: the object's screen box (rect: screenRect's) is at most frame.swMaxPixels per
// side, its triangles are small (SW_RASTER_MAX_AREA_PER_TRIANGLE) and it lies wholly beyond the near plane
// (sw_raster.comp needs no clipping and keeps its edge functions within 32 bits).
bool smallOnScreen(bool rect, vec2 lo, vec2 hi, uint triangles) {
  vec2 extent = (hi - lo) * 0.5 * frame.viewport.xy;
  return rect && max(extent.x, extent.y) <= frame.swMaxPixels &&
         extent.x * extent.y <= SW_RASTER_MAX_AREA_PER_TRIANGLE * float(triangles);
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
  int level = min(int(ceil(log2(float(extent)))), int(frame.pyramidLevels) - 1);
  if ((1 << level) < extent) level = min(level + 1, int(frame.pyramidLevels) - 1);  // guard log2 rounding
  // The object's nearest possible depth, rounded towards nearer.
  float nearest = frame.nearPlane / -(v.z + rr) * (1.0 + 1e-5);
  // That level's texels may reach past the rectangle by up to their own size per axis (up to 4x its area): what it
  // does not prove occluded is tested again three levels finer, in at most 9x9 texels that reach past it by at most
  // 1/4 of its extent per axis. The peer field (1M kittens): 61,487 objects drawn with the coarse level alone,
  // 45,049 two levels finer, 41,297 three levels finer, 38,110 at full resolution. That runs in the refinement
  // dispatch, dense over the few objects concerned (on lavapipe a loop here would run in every SIMD batch that
  // holds one of them).
  int fine = max(level - 3, 0);
  if (refine) return nearest < farthestDepth(a, b, fine) ? 1u : 0u;
  if (nearest < farthestDepth(a, b, level)) return 1u;
  return fine < level ? 4u : 0u;
}

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

// Lists the lanes where `mine` holds for this phase's cluster dispatch: (object ID, LOD) entries after the
// refinement list, the early phase's from the start, the late phase's from the end; the dispatch size grows with
// the count (at most CLUSTER_MAX_WORKGROUPS workgroups, which stride over the list).
void appendToClusterList(bool mine, uint id, uint lod) {
  uvec4 ballot = subgroupBallot(mine);
  uint count = subgroupBallotBitCount(ballot);
  if (count == 0u) return;
  uint first = 0u;
  uint args = CLUSTER_ARGS + pc.phase * CLUSTER_ARGS_UINTS;
  if (subgroupElect()) {
    first = atomicAdd(stats[args], count);
    atomicMax(stats[args + 1u], min(first + count, CLUSTER_MAX_WORKGROUPS));
  }
  first = subgroupBroadcastFirst(first);
  uint e = first + subgroupBallotExclusiveBitCount(ballot);
  if (mine && e < frame.objectCount) {
    uint at = pc.phase == CULL_PHASE_LATE ? frame.objectCount - 1u - e : e;
    uint word = 2u * (VISIBLE_LIST_HEADER + frame.objectCount) + 2u * at;
    visibleList[word] = id;
    visibleList[word + 1u] = lod;
  }
}

#if CULL_CLUSTER_PASS
shared uint hwClusters[CULL_WORKGROUP_SIZE / 32];  // bit i: the cluster of invocation i goes to the hardware raster

// CULL_CLUSTERS (its own pipeline, cull_clusters.comp: in one shader with the object cull, lavapipe's late cull over
// 1M objects took 90 ms instead of 50): one workgroup per listed object at a time, a thread per cluster.
void main() {
  const uint args = CLUSTER_ARGS + pc.phase * CLUSTER_ARGS_UINTS;
  const uint count = min(stats[args], frame.objectCount);
  const uint counter = pc.phase == CULL_PHASE_LATE ? STAT_DRAW_COUNT_LATE : STAT_DRAW_COUNT;
  if (gl_LocalInvocationIndex < CULL_WORKGROUP_SIZE / 32u) hwClusters[gl_LocalInvocationIndex] = 0u;
  barrier();
  for (uint e = gl_WorkGroupID.x; e < count; e += gl_NumWorkGroups.x) {
    uint at = pc.phase == CULL_PHASE_LATE ? frame.objectCount - 1u - e : e;
    uint word = 2u * (VISIBLE_LIST_HEADER + frame.objectCount) + 2u * at;
    uint id = visibleList[word], lod = visibleList[word + 1u];
    ObjectData o = objectAt(id);
    uint list = objectDrawList(o.flags);
    LodData ld = meshLod(o.meshIndex, lod);
    int vertexOffset = int(meshes[o.meshIndex].vertexOffset);
    uint triangles = ld.indexCount / 3u;
    uint n = (triangles + CLUSTER_TRIANGLES - 1u) / CLUSTER_TRIANGLES;
    vec3 eye = cameraInObjectSpace(o);
    bool coneTest = list != DRAW_LIST_OPAQUE_DOUBLE_SIDED && list != DRAW_LIST_MASKED_DOUBLE_SIDED;
    bool swList = frame.swRaster != 0u && drawLists[list].w != 0u && CLUSTER_TRIANGLES <= frame.swMaxTriangles;
    bool pyramidTest = frame.cullMode == CULL_OCCLUSION && pc.phase == CULL_PHASE_LATE;
    uvec4 region = drawLists[list];
    uint first = pc.phase == CULL_PHASE_LATE ? region.y : region.x;
    for (uint b = 0u; b < n; b += CULL_WORKGROUP_SIZE) {
      uint c = b + gl_LocalInvocationIndex;
      bool valid = c < n;
      uint culledFrustum = 0u, culledBack = 0u, culledOccluded = 0u;
      bool keep = false, sw = false;
      uint clusterTriangles = valid ? min(triangles - c * CLUSTER_TRIANGLES, CLUSTER_TRIANGLES) : 0u;
      if (valid) {
        ClusterData cd = clusters[ld.firstCluster + c];
        vec3 centre = objectToCamera(o, cd.sphere.xyz);
        float r = cd.sphere.w * o.maxScale;
        // Back-face cone in object space (an affine map keeps which side of a plane the camera is on; a mirroring
        // one is drawn by a FLIPPED list, which keeps the object-space front faces), from its apex, with a margin of
        // 1e-3 on the cosine, where snapping could turn an edge-on triangle's projected winding.
        vec3 toApex = cd.apex.xyz - eye;
        bool back = coneTest && dot(toApex, cd.cone.xyz) >= (cd.cone.w + 1e-3) * length(toApex);
        vec3 v;
        float rr;
        vec2 lo, hi;
        bool rect = screenRect(centre, r, v, rr, lo, hi);
        if (!frustumVisible(centre, r)) {
          culledFrustum = 1u;
        } else if (back) {
          culledBack = 1u;
        } else if (occlusionTest(rect, v, rr, lo, hi, false, pyramidTest) % 4u != 0u) {  // 1, 2: occluded, no pixel
          culledOccluded = 1u;
        } else {
          keep = true;
          sw = swList && smallOnScreen(rect, lo, hi, clusterTriangles);
        }
      }
      // Hardware draws: one per run of consecutive surviving clusters among the workgroup's (a mask of them in shared
      // memory; on lavapipe a draw costs about as much as 50 triangles, so runs matter more than the clusters culled
      // between them).
      bool hw = keep && !sw;
      uint i = gl_LocalInvocationIndex;
      if (hw) atomicOr(hwClusters[i >> 5u], 1u << (i & 31u));
      barrier();
      bool previous = i > 0u && ((hwClusters[(i - 1u) >> 5u] >> ((i - 1u) & 31u)) & 1u) != 0u;
      bool startsRun = hw && !previous;
      // The run ends at the first cluster after this one that is not drawn by the hardware raster.
      uint end = CULL_WORKGROUP_SIZE;
      for (uint k = (i + 1u) >> 5u; k < CULL_WORKGROUP_SIZE / 32u && end == CULL_WORKGROUP_SIZE; ++k) {
        uint after = ~hwClusters[k] & (k == (i + 1u) >> 5u ? ~0u << ((i + 1u) & 31u) : ~0u);
        if (i + 1u < CULL_WORKGROUP_SIZE && after != 0u) end = 32u * k + uint(findLSB(after));
      }
      uint runClusters = end - i;
      barrier();  // every lane has read the mask: cleared for the next clusters
      if (i < CULL_WORKGROUP_SIZE / 32u) hwClusters[i] = 0u;
      barrier();
      uint runTriangles = startsRun ? min(triangles - c * CLUSTER_TRIANGLES, runClusters * CLUSTER_TRIANGLES) : 0u;
      uvec4 drawBallot = subgroupBallot(startsRun), swBallot = subgroupBallot(sw);
      uint hwCount = subgroupBallotBitCount(drawBallot), swCount = subgroupBallotBitCount(swBallot);
      uint tested = subgroupAdd(valid ? 1u : 0u);
      uint frustumSum = subgroupAdd(culledFrustum), backSum = subgroupAdd(culledBack);
      uint occludedSum = subgroupAdd(culledOccluded);
      uint triangleSum = subgroupAdd(runTriangles + (sw ? clusterTriangles : 0u));
      uint swTriangleSum = subgroupAdd(sw ? clusterTriangles : 0u);
      uint hwBase = 0u, swBase = 0u;
      if (subgroupElect()) {
        if (tested > 0u) atomicAdd(stats[STAT_CLUSTERS_TESTED], tested);
        if (frustumSum > 0u) atomicAdd(stats[STAT_CLUSTERS_FRUSTUM], frustumSum);
        if (backSum > 0u) atomicAdd(stats[STAT_CLUSTERS_BACKFACING], backSum);
        if (occludedSum > 0u) atomicAdd(stats[STAT_CLUSTERS_OCCLUDED], occludedSum);
        if (hwCount + swCount > 0u) {
          atomicAdd(stats[counter], hwCount + swCount);
          atomicAdd(stats[STAT_CLUSTER_DRAWS], hwCount + swCount);
          atomicAdd(stats[STAT_TRIANGLES_DRAWN], triangleSum);
        }
        if (hwCount > 0u) hwBase = atomicAdd(stats[STAT_LIST_DRAWS + pc.phase * DRAW_LISTS + list], hwCount);
        if (swCount > 0u) {
          swBase = atomicAdd(stats[STAT_SW_DRAWS + pc.phase * DRAW_LISTS + list], swCount);
          atomicAdd(stats[STAT_SW_TRIANGLES], swTriangleSum);
          uint swArgs = SW_ARGS + pc.phase * SW_ARGS_UINTS;
          atomicMax(stats[swArgs + SW_ARGS_DISPATCH], min((swBase + swCount + 7u) / 8u, SW_RASTER_MAX_WORKGROUPS));
          atomicMax(stats[swArgs + SW_ARGS_MERGE], 3u);
        }
      }
      hwBase = subgroupBroadcastFirst(hwBase);
      swBase = subgroupBroadcastFirst(swBase);
      uint slot = startsRun ? hwBase + subgroupBallotExclusiveBitCount(drawBallot)
                            : swBase + subgroupBallotExclusiveBitCount(swBallot);
      if (startsRun || sw) {
        if (slot >= region.z) {  // (the cull pass reserved room for every cluster: never, but counted)
          atomicAdd(stats[STAT_DRAW_OVERFLOW], 1u);
        } else {
          if (sw) slot = region.z - 1u - slot;
          uint drawTriangles = sw ? clusterTriangles : runTriangles;
          draws[first + slot] = DrawCommand(3u * drawTriangles, 1u, ld.firstIndex + 3u * CLUSTER_TRIANGLES * c,
                                            vertexOffset, id);
        }
      }
    }
  }
}

#else
void main() {
  // The early phase of occlusion culling runs over last frame's visible list (indirect dispatch, one thread per
  // listed object): a heavily occluded scene pays for the few it drew, not for every object it holds.
  // The late phase's refinement dispatch runs over the list its first dispatch wrote.
  const bool refine = pc.phase == CULL_PHASE_LATE && pc.variant == CULL_REFINE;
  const uint refineList = VISIBLE_LIST_HEADER + frame.objectCount;
  const bool listed = (pc.phase == CULL_PHASE_EARLY && frame.cullMode == CULL_OCCLUSION) || refine;
  const uint listBase = refine ? refineList : 0u;
  uint id = gl_GlobalInvocationID.x;
  bool valid = id < (listed ? min(visibleList[listBase], frame.objectCount) : frame.objectCount);
  if (listed) id = valid ? visibleList[listBase + VISIBLE_LIST_HEADER + id] : 0u;
  // Hidden objects and free slots are skipped in every phase. The late phase clears their history bit: the early
  // phase draws only listed objects and the late phase takes a set bit for "drawn early", so a bit without a list
  // entry would lose the object when it is shown again or its slot reused (a hidden object is never listed).
  if (valid && (objectAt(id).flags & OBJECT_FLAG_HIDDEN) != 0u) {
    valid = false;
    if (frame.cullMode == CULL_OCCLUSION && pc.phase == CULL_PHASE_LATE && !refine && history[id] != 0u)
      history[id] = 0u;
  }
  bool draw = false;
  uint lod = 0;
  uint meshIndex = 0;
  uint list = DRAW_LIST_NONE;
  uint frustumCulled = 0, occluded = 0, subpixel = 0;
  bool sw = false;  // routed to the software micro-raster
  bool clustered = false;  // listed for the cluster dispatch
  uint clusterCount = 0u;
  bool visibleNow = false;  // late phase: listed for the next frame's early phase
  bool deferred = false;  // late phase, first dispatch: listed for the refinement dispatch, decided there
  if (valid) {
    // Only the fields needed are loaded: copying the whole 224-byte MeshData per thread made the pass
    // ~3x slower on lavapipe (0.71 s vs 0.23 s per million objects, all culled, same machine and load).
    ObjectData o = objectAt(id);
    meshIndex = o.meshIndex;
    list = objectDrawList(o.flags);  // set at upload (drawListOf): no material fetch per object
    vec4 sphere = meshBoundsSphere(meshIndex);
    vec3 c = objectToCamera(o, sphere.xyz);
    float r = sphere.w * o.maxScale;
    vec3 v;
    float rr;
    vec2 lo, hi;
    bool rect = screenRect(c, r, v, rr, lo, hi);  // (the occlusion test's and the micro-raster routing's)
    bool inFrustum = frame.cullMode == CULL_NONE || frustumVisible(c, r);
    if (frame.cullMode != CULL_OCCLUSION) {
      draw = inFrustum && list != DRAW_LIST_NONE;  // BLEND objects: the transparency pass
      frustumCulled = inFrustum ? 0u : 1u;
    } else if (pc.phase == CULL_PHASE_EARLY) {
      draw = inFrustum && history[id] != 0u && list != DRAW_LIST_NONE;  // culled ones: counted late
    } else {
      bool drawnEarly = inFrustum && history[id] != 0u;  // exactly the early phase's decision
      uint test = inFrustum ? occlusionTest(rect, v, rr, lo, hi, refine, true) : 3u;
      deferred = test == 4u;
      if (deferred) test = 5u;  // nothing counted, written or drawn here
      frustumCulled = test == 3u ? 1u : 0u;
      occluded = test == 1u ? 1u : 0u;
      subpixel = test == 2u ? 1u : 0u;
      if (!deferred) history[id] = test == 0u ? 1u : 0u;
      draw = test == 0u && !drawnEarly && list != DRAW_LIST_NONE;
      visibleNow = test == 0u;
    }
    if (draw && frame.lodErrorPixels > 0.0) {
      // Projected error of level l at the nearest point of the sphere: error * scale * lodScale / dist.
      float dist = length(c) - r;
      if (dist > frame.nearPlane) {
        for (uint l = meshes[meshIndex].lodCount - 1; l > 0; --l) {
          if (meshLod(meshIndex, l).error * o.maxScale * frame.lodScale <= frame.lodErrorPixels * dist) {
            lod = l;
            break;
          }
        }
      }
    }
    // Small objects of the lists the micro-raster may take go to sw_raster.comp (FrameData.swRaster): they fill their
    // list's region from its end, with a count of their own.
    if (draw && frame.swRaster != 0u && drawLists[list].w != 0u) {
      uint lodTriangles = meshLod(meshIndex, lod).indexCount / 3u;
      sw = lodTriangles <= frame.swMaxTriangles && smallOnScreen(rect, lo, hi, lodTriangles);
    }
    // The hardware raster's objects whose LOD has clusters: to the cluster dispatch.
    vec2 extent = (hi - lo) * 0.5 * frame.viewport.xy;
    if (draw && !sw && frame.clusterCull != 0u && frame.cullMode != CULL_NONE &&
        (!rect || max(extent.x, extent.y) > CLUSTER_MIN_PIXELS)) {
      LodData ld = meshLod(meshIndex, lod);
      if (ld.firstCluster != CLUSTER_NONE) {
        clustered = true;
        clusterCount = (ld.indexCount / 3u + CLUSTER_TRIANGLES - 1u) / CLUSTER_TRIANGLES;
      }
    }
  }
  // Cluster draws are reserved per list and phase (one atomic per subgroup and list present): an object whose clusters
  // do not fit the list's reserve is drawn whole, so that its region never overflows. (Only in subgroups that have a
  // clustered object: on lavapipe the atomics would cost every other subgroup a loop over its lanes.)
  if (subgroupAny(clustered)) {
    bool claiming = clustered;
    while (subgroupAny(claiming)) {
      uint current = subgroupMin(claiming ? list : DRAW_LIST_NONE);
      bool mine = claiming && list == current;
      uint want = mine ? clusterCount : 0u;
      uint total = subgroupAdd(want), before = subgroupExclusiveAdd(want);
      uint reserved = 0u;
      if (subgroupElect()) reserved = atomicAdd(stats[STAT_CLUSTER_RESERVED + pc.phase * DRAW_LISTS + current], total);
      reserved = subgroupBroadcastFirst(reserved);
      if (mine && reserved + before + clusterCount > drawLists[DRAW_LISTS + list].x) clustered = false;
      claiming = claiming && !mine;
    }
    appendToClusterList(clustered, id, lod);
    uint clusteredSum = subgroupAdd(clustered ? 1u : 0u);
    if (clusteredSum > 0u && subgroupElect()) atomicAdd(stats[STAT_CLUSTER_OBJECTS], clusteredSum);
  }
  bool whole = draw && !clustered;  // a draw command of its own
  // The next frame's visible list, and the refinement dispatch's.
  appendToList(0u, visibleNow, id);
  if (pc.phase == CULL_PHASE_LATE && !refine) appendToList(refineList, deferred, id);
  uint culledSum = subgroupAdd(frustumCulled);
  uint occludedSum = subgroupAdd(occluded);
  uint subpixelSum = subgroupAdd(subpixel);
  // Slots: one atomic per subgroup and draw list present in it (a scene with one list loops once).
  const uint counter = pc.phase == CULL_PHASE_LATE ? STAT_DRAW_COUNT_LATE : STAT_DRAW_COUNT;
  uint refinedSum = refine ? subgroupAdd(valid ? 1u : 0u) : 0u;
  if (subgroupElect()) {
    if (refinedSum > 0) atomicAdd(stats[STAT_REFINE_TESTED], refinedSum);
    if (refine && occludedSum > 0) atomicAdd(stats[STAT_REFINE_OCCLUDED], occludedSum);
    if (culledSum > 0) atomicAdd(stats[STAT_FRUSTUM_CULLED], culledSum);
    if (occludedSum > 0) atomicAdd(stats[STAT_OCCLUSION_CULLED], occludedSum);
    if (subpixelSum > 0) atomicAdd(stats[STAT_SUBPIXEL_CULLED], subpixelSum);
  }
  uint slot = 0;
  bool pending = whole;
  uint key = sw ? list + DRAW_LISTS : list;  // hardware draws of list l: l; micro-raster draws: DRAW_LISTS + l
  while (subgroupAny(pending)) {
    uint current = subgroupMin(pending ? key : DRAW_LIST_NONE);
    bool mine = pending && key == current;
    uvec4 ballot = subgroupBallot(mine);
    uint count = subgroupBallotBitCount(ballot);
    uint base = 0;
    if (subgroupElect()) {
      atomicAdd(stats[counter], count);
      uint listCounter = current < DRAW_LISTS ? STAT_LIST_DRAWS + pc.phase * DRAW_LISTS + current
                                              : STAT_SW_DRAWS + pc.phase * DRAW_LISTS + current - DRAW_LISTS;
      base = atomicAdd(stats[listCounter], count);
      if (current >= DRAW_LISTS) {  // the micro-raster and its merge run this phase (sw_raster.comp grid-strides)
        uint args = SW_ARGS + pc.phase * SW_ARGS_UINTS;
        atomicMax(stats[args + SW_ARGS_DISPATCH], min((base + count + 7u) / 8u, SW_RASTER_MAX_WORKGROUPS));
        atomicMax(stats[args + SW_ARGS_MERGE], 3u);
      }
    }
    base = subgroupBroadcastFirst(base);
    if (mine) slot = base + subgroupBallotExclusiveBitCount(ballot);
    pending = pending && !mine;
  }
  if (!draw) return;
  if (whole) {
    uvec4 region = drawLists[list];  // x: early first slot, y: late first slot, z: capacity
    if (slot >= region.z) {
      atomicAdd(stats[STAT_DRAW_OVERFLOW], 1u);
      return;
    }
    LodData l = meshLod(meshIndex, lod);
    uint first = pc.phase == CULL_PHASE_LATE ? region.y : region.x;
    if (sw) slot = region.z - 1u - slot;
    draws[first + slot] = DrawCommand(l.indexCount, 1u, l.firstIndex, int(meshes[meshIndex].vertexOffset), id);
    // Counters: one atomic per subgroup (and LOD level present), not per object: on lavapipe every lane's atomic on
    // the same word is a locked operation bouncing between the cores.
    uint triangles = subgroupAdd(l.indexCount / 3u);
    uint swTriangles = subgroupAdd(sw ? l.indexCount / 3u : 0u);
    if (subgroupElect()) {
      atomicAdd(stats[STAT_TRIANGLES_DRAWN], triangles);
      if (swTriangles > 0u) atomicAdd(stats[STAT_SW_TRIANGLES], swTriangles);
    }
  }
  bool counting = true;
  while (subgroupAny(counting)) {
    uint current = subgroupMin(counting ? lod : 0xFFFFFFFFu);
    uint n = subgroupBallotBitCount(subgroupBallot(counting && lod == current));
    if (subgroupElect()) atomicAdd(stats[STAT_LOD_HISTOGRAM + current], n);
    counting = counting && lod != current;
  }
}
#endif
