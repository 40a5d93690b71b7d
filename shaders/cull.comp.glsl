#version 460
// Cull pass: one thread per object. Bounding sphere vs the camera-relative frustum planes, LOD by
// projected error, then append a VkDrawIndexedIndirectCommand (firstInstance = object ID). Slots are
// allocated with one atomic per subgroup (ballot + prefix count).
//
// Occlusion mode runs this twice per frame (Hill & Collin's two-phase scheme as used by niagara):
//   early: objects visible at the end of last frame (history, dispatched over its list) -> frustum + LOD -> drawn
//          first;
//   late:  every object -> frustum (cull_sieve.comp; the objects inside are listed) -> sub-pixel and depth-pyramid
//          tests (cull_occlusion.comp, pyramid of the early depth; history := visible) -> the objects visible and
//          not already drawn early are listed, and this shader's late draw dispatch (CULL_LATE_DRAW) takes them.
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
#include "cull_tests.glsl"

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

void main() {
  // The early phase of occlusion culling runs over last frame's visible list (indirect dispatch, one thread per
  // listed object): a heavily occluded scene pays for the few it drew, not for every object it holds.
  // The late draw dispatch runs over the objects the occlusion test (cull_occlusion.comp) listed to draw late.
  const bool lateDraw = pc.phase == CULL_PHASE_LATE;  // (only occlusion mode has a late phase)
  const bool listed = (pc.phase == CULL_PHASE_EARLY && frame.cullMode == CULL_OCCLUSION) || lateDraw;
  const uint listBase = lateDraw ? LATE_DRAW_LIST_WORD(frame.objectCount) : 0u;
  uint id = gl_GlobalInvocationID.x;
  bool valid = id < (listed ? min(visibleList[listBase], frame.objectCount) : frame.objectCount);
  if (listed) id = valid ? visibleList[listBase + VISIBLE_LIST_HEADER + id] : 0u;
  // Hidden objects and free slots are skipped in every phase (the sieve clears their history bit: the early phase
  // draws only listed objects and the late phase takes a set bit for "drawn early", so a bit without a list entry
  // would lose the object when it is shown again or its slot reused; a hidden object is never listed).
  if (valid && (objectAt(id).flags & OBJECT_FLAG_HIDDEN) != 0u) valid = false;
  bool draw = false;
  uint lod = 0;
  uint meshIndex = 0;
  uint list = DRAW_LIST_NONE;
  uint frustumCulled = 0;
  bool sw = false;  // routed to the software micro-raster
  bool clustered = false;  // listed for the cluster dispatch
  uint clusterCount = 0u;
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
    bool rect = screenRect(c, r, v, rr, lo, hi);  // (the micro-raster routing's)
    if (lateDraw) {
      draw = true;  // inside the frustum, visible now, not drawn early, in a draw list (cull_occlusion.comp)
    } else {
      bool inFrustum = frame.cullMode == CULL_NONE || frustumVisible(c, r);
      if (frame.cullMode != CULL_OCCLUSION) {
        draw = inFrustum && list != DRAW_LIST_NONE;  // BLEND objects: the transparency pass
        frustumCulled = inFrustum ? 0u : 1u;
      } else {
        draw = inFrustum && history[id] != 0u && list != DRAW_LIST_NONE;  // culled ones: counted late
      }
    }
    if (draw && frame.lodErrorPixels > 0.0) {
      // Projected error of level l at the nearest point of the sphere: error * scale * lodScale / dist
      // (orthographic: error * scale * lodScale at any distance, so dist = 1).
      float dist = orthographic() ? 1.0 : length(c) - r;
      if (orthographic() || dist > frame.nearPlane) {
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
    bool capped = false;  // small enough for the micro-raster, but its level has more triangles than one draw may
    if (draw && frame.swRaster != 0u && drawLists[list].w != 0u) {
      uint lodTriangles = meshLod(meshIndex, lod).indexCount / 3u;
      bool small = smallOnScreen(rect, lo, hi, lodTriangles);
      sw = lodTriangles <= frame.swMaxTriangles && small;
      capped = small && !sw;
    }
    // The hardware raster's objects whose LOD has clusters, if large on screen or capped (then their clusters, 64
    // triangles each, go to the micro-raster): to the cluster dispatch.
    vec2 extent = (hi - lo) * 0.5 * frame.viewport.xy;
    if (draw && !sw && frame.clusterCull != 0u && frame.cullMode != CULL_NONE &&
        (!rect || max(extent.x, extent.y) > CLUSTER_MIN_PIXELS || capped)) {
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
  uint culledSum = subgroupAdd(frustumCulled);
  const uint counter = pc.phase == CULL_PHASE_LATE ? STAT_DRAW_COUNT_LATE : STAT_DRAW_COUNT;
  if (subgroupElect() && culledSum > 0) atomicAdd(stats[STAT_FRUSTUM_CULLED], culledSum);
  uint key = sw ? list + DRAW_LISTS : list;  // hardware draws of list l: l; micro-raster draws: DRAW_LISTS + l
  uint slot = takeDrawSlots(whole, key, pc.phase, counter);
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
