#version 460
// Cluster dispatch of the cull pass (CULL_CLUSTERS; cull_pass.cpp records it after each phase's object cull, an
// indirect dispatch sized by the clusters' list in the stats buffer): one workgroup per object that phase listed, a
// thread per cluster of its LOD level. Each cluster is tested against the frustum, its back-face cone and, in the
// late phase of occlusion culling, the depth pyramid; a small survivor goes to the micro-raster, the others are drawn
// as one draw per run of consecutive survivors. Its own pipeline: in one shader with the object cull, lavapipe's late
// cull over 1M objects took 90 ms instead of 50.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "cull_tests.glsl"

shared uint hwClusters[CULL_WORKGROUP_SIZE / 32];  // bit i: the cluster of invocation i goes to the hardware raster

// One workgroup per listed object at a time (the workgroups stride over the list), a thread per cluster.
void main() {
  const uint args = CLUSTER_ARGS + pc.phase * CLUSTER_ARGS_UINTS;
  const uint count = min(stats[args], frame.objectCount);
  const uint counter = pc.phase == CULL_PHASE_LATE ? STAT_DRAW_COUNT_LATE : STAT_DRAW_COUNT;
  if (gl_LocalInvocationIndex < CULL_WORKGROUP_SIZE / 32u) hwClusters[gl_LocalInvocationIndex] = 0u;
  barrier();
  // The counters, per lane over every cluster it takes, added to the stats once at the end (on lavapipe each atomic
  // on a word every core writes is a locked operation bouncing between the cores: per batch of clusters they cost
  // more than the tests). Only the draw slots are taken as the clusters go.
  uint tested = 0u, frustumCulled = 0u, backfacing = 0u, occluded = 0u, deferred = 0u;
  uint drawCount = 0u, drawnTriangles = 0u, swTriangles = 0u, swDispatch = 0u;
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
    vec4 eye = eyeInObjectSpace(o);
    bool coneTest = list != DRAW_LIST_OPAQUE_DOUBLE_SIDED && list != DRAW_LIST_MASKED_DOUBLE_SIDED;
    bool swList = clustersMayUseMicroRaster(pc.phase, list);
    bool pyramidTest = frame.cullMode == CULL_OCCLUSION && pc.phase == CULL_PHASE_LATE;
    // Early cluster occlusion (CULL_CLUSTER_RETEST): the early phase tests against last frame's pyramid too, and
    // defers what it hides to the late phase's retest.
    bool guess = frame.earlyClusterOcclusion != 0u && pc.phase == CULL_PHASE_EARLY;
    uvec4 region = drawLists[list];
    uint first = pc.phase == CULL_PHASE_LATE ? region.y : region.x;
    for (uint b = 0u; b < n; b += CULL_WORKGROUP_SIZE) {
      uint c = b + gl_LocalInvocationIndex;
      bool valid = c < n;
      uint culledFrustum = 0u, culledBack = 0u, culledOccluded = 0u;
      bool keep = false, sw = false, defer = false, rect = false;
      vec2 lo = vec2(0.0), hi = vec2(0.0);
      uint clusterTriangles = valid ? min(triangles - c * CLUSTER_TRIANGLES, CLUSTER_TRIANGLES) : 0u;
      if (valid) {
        ClusterData cd = clusters[ld.firstCluster + c];
        vec3 centre = objectToCamera(o, cd.sphere.xyz);
        float r = cd.sphere.w * o.maxScale;
        // Back-face cone in object space (an affine map keeps which side of a plane the camera is on; a mirroring
        // one is drawn by a FLIPPED list, which keeps the object-space front faces), from its apex, with a margin of
        // 1e-3 on the cosine, where snapping could turn an edge-on triangle's projected winding.
        vec3 toApex = cd.apex.xyz * eye.w - eye.xyz;  // (orthographic: the view direction)
        bool back = coneTest && dot(toApex, cd.cone.xyz) >= (cd.cone.w + 1e-3) * length(toApex);
        vec3 v;
        float rr;
        rect = screenRect(centre, r, v, rr, lo, hi);
        if (!frustumVisible(centre, r)) {
          culledFrustum = 1u;
        } else if (back) {
          culledBack = 1u;
        } else {
          uint test = occlusionTest(rect, v, rr, lo, hi, false, pyramidTest || guess) % 4u;
          defer = guess && test == 1u;  // hidden by last frame's pyramid: retested late
          keep = test == 0u;
          culledOccluded = test != 0u && !defer ? 1u : 0u;  // 1, 2: occluded, no pixel centre
        }
      }
      // Each deferred cluster takes a retest entry and one late cluster draw (one atomic each per subgroup; the
      // workgroup's object, hence its list, is uniform); one that finds no room is drawn now.
      if (subgroupAny(defer)) {
        uvec4 ballot = subgroupBallot(defer);
        uint want = subgroupBallotBitCount(ballot), before = subgroupBallotExclusiveBitCount(ballot);
        uint reserved = 0u, at = 0u;
        if (subgroupElect()) {
          reserved = atomicAdd(stats[STAT_CLUSTER_RESERVED + CULL_PHASE_LATE * DRAW_LISTS + list], want);
          at = atomicAdd(stats[RETEST_ARGS], want);
          atomicMax(stats[RETEST_ARGS + 1u],
                    min((at + want + CULL_WORKGROUP_SIZE - 1u) / CULL_WORKGROUP_SIZE, CLUSTER_MAX_WORKGROUPS));
        }
        reserved = subgroupBroadcastFirst(reserved) + before;
        at = subgroupBroadcastFirst(at) + before;
        bool room = reserved < drawLists[DRAW_LISTS + list].x;
        if (defer && at < RETEST_CAPACITY(frame.objectCount)) {
          uint word = RETEST_LIST_WORD(frame.objectCount) + 2u * at;
          visibleList[word] = room ? id : RETEST_NONE;
          visibleList[word + 1u] = lod << 24 | c;
        }
        if (defer && !(room && at < RETEST_CAPACITY(frame.objectCount))) {
          defer = false;  // (the retest skips its entry)
          keep = true;
        }
      }
      sw = keep && swList && smallOnScreen(rect, lo, hi, clusterTriangles);
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
      tested += valid ? 1u : 0u;
      frustumCulled += culledFrustum;
      backfacing += culledBack;
      occluded += culledOccluded;
      deferred += defer ? 1u : 0u;
      drawCount += startsRun || sw ? 1u : 0u;
      drawnTriangles += runTriangles + (sw ? clusterTriangles : 0u);
      swTriangles += sw ? clusterTriangles : 0u;
      uint hwBase = 0u, swBase = 0u;
      if (subgroupElect()) {
        if (hwCount > 0u) hwBase = atomicAdd(stats[STAT_LIST_DRAWS + pc.phase * DRAW_LISTS + list], hwCount);
        if (swCount > 0u) swBase = atomicAdd(stats[STAT_SW_DRAWS + pc.phase * DRAW_LISTS + list], swCount);
      }
      hwBase = subgroupBroadcastFirst(hwBase);
      swBase = subgroupBroadcastFirst(swBase);
      if (swCount > 0u) swDispatch = max(swDispatch, min((swBase + swCount + 7u) / 8u, SW_RASTER_MAX_WORKGROUPS));
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
  uint testedSum = subgroupAdd(tested), frustumSum = subgroupAdd(frustumCulled), backSum = subgroupAdd(backfacing);
  uint occludedSum = subgroupAdd(occluded), deferredSum = subgroupAdd(deferred), drawSum = subgroupAdd(drawCount);
  uint triangleSum = subgroupAdd(drawnTriangles), swTriangleSum = subgroupAdd(swTriangles);
  uint swDispatchMax = subgroupMax(swDispatch);
  if (subgroupElect()) {
    if (testedSum > 0u) atomicAdd(stats[STAT_CLUSTERS_TESTED], testedSum);
    if (frustumSum > 0u) atomicAdd(stats[STAT_CLUSTERS_FRUSTUM], frustumSum);
    if (backSum > 0u) atomicAdd(stats[STAT_CLUSTERS_BACKFACING], backSum);
    if (occludedSum > 0u) atomicAdd(stats[STAT_CLUSTERS_OCCLUDED], occludedSum);
    if (deferredSum > 0u) atomicAdd(stats[STAT_CLUSTERS_DEFERRED], deferredSum);
    if (drawSum > 0u) {
      atomicAdd(stats[counter], drawSum);
      atomicAdd(stats[STAT_CLUSTER_DRAWS], drawSum);
      atomicAdd(stats[STAT_TRIANGLES_DRAWN], triangleSum);
    }
    if (swDispatchMax > 0u) {
      uint swArgs = SW_ARGS + pc.phase * SW_ARGS_UINTS;
      atomicAdd(stats[STAT_SW_TRIANGLES], swTriangleSum);
      atomicMax(stats[swArgs + SW_ARGS_DISPATCH], swDispatchMax);
      atomicMax(stats[swArgs + SW_ARGS_MERGE], 3u);
    }
  }
}
