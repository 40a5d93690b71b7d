#version 460
// Retest of the deferred clusters (CULL_CLUSTER_RETEST; cull_pass.cpp records it in the late phase, after its
// cluster dispatch, an indirect dispatch sized by RETEST_ARGS): one thread per cluster that the early phase did not
// draw because last frame's pyramid hid it. Each is tested against this frame's pyramid (of the early depth, as
// every late test) and drawn if it is not hidden: to the micro-raster if small, else by the hardware raster, one
// draw each, in the late phase's regions (the early phase reserved a late cluster draw for each entry).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "cull_tests.glsl"

void main() {
  const uint count = min(stats[RETEST_ARGS], RETEST_CAPACITY(frame.objectCount));
  const uint stride = gl_NumWorkGroups.x * CULL_WORKGROUP_SIZE;
  for (uint base = gl_WorkGroupID.x * CULL_WORKGROUP_SIZE; base < count; base += stride) {
    uint e = base + gl_LocalInvocationIndex;
    uint id = RETEST_NONE, packed = 0u;
    if (e < count) {
      uint word = RETEST_LIST_WORD(frame.objectCount) + 2u * e;
      id = visibleList[word];
      packed = visibleList[word + 1u];
    }
    bool valid = id != RETEST_NONE;
    bool draw = false, sw = false;
    uint list = DRAW_LIST_NONE, occluded = 0u, clusterTriangles = 0u, firstIndex = 0u;
    int vertexOffset = 0;
    if (valid) {
      uint lod = packed >> 24, c = packed & 0xFFFFFFu;
      ObjectData o = objectAt(id);
      list = objectDrawList(o.flags);
      LodData ld = meshLod(o.meshIndex, lod);
      vertexOffset = int(meshes[o.meshIndex].vertexOffset);
      clusterTriangles = min(ld.indexCount / 3u - c * CLUSTER_TRIANGLES, CLUSTER_TRIANGLES);
      firstIndex = ld.firstIndex + 3u * CLUSTER_TRIANGLES * c;
      ClusterData cd = clusters[ld.firstCluster + c];
      vec3 v;
      float rr;
      vec2 lo, hi;
      bool rect = screenRect(objectToCamera(o, cd.sphere.xyz), cd.sphere.w * o.maxScale, v, rr, lo, hi);
      if (occlusionTest(rect, v, rr, lo, hi, false, true) % 4u != 0u) {  // 1, 2: occluded, no pixel centre
        occluded = 1u;
      } else {
        draw = true;
        sw = clustersMayUseMicroRaster(CULL_PHASE_LATE, list) && smallOnScreen(rect, lo, hi, clusterTriangles);
      }
    }
    uint occludedSum = subgroupAdd(occluded), drawnSum = subgroupAdd(draw ? 1u : 0u);
    uint triangleSum = subgroupAdd(draw ? clusterTriangles : 0u), swTriangleSum = subgroupAdd(sw ? clusterTriangles : 0u);
    if (subgroupElect()) {
      if (occludedSum > 0u) atomicAdd(stats[STAT_CLUSTERS_OCCLUDED], occludedSum);
      if (drawnSum > 0u) {
        atomicAdd(stats[STAT_CLUSTER_DRAWS], drawnSum);
        atomicAdd(stats[STAT_CLUSTERS_RECOVERED], drawnSum);
        atomicAdd(stats[STAT_TRIANGLES_DRAWN], triangleSum);
      }
      if (swTriangleSum > 0u) atomicAdd(stats[STAT_SW_TRIANGLES], swTriangleSum);
    }
    uint slot = takeDrawSlots(draw, sw ? list + DRAW_LISTS : list, CULL_PHASE_LATE, STAT_DRAW_COUNT_LATE);
    if (draw) {
      uvec4 region = drawLists[list];  // x: early first slot, y: late first slot, z: capacity
      if (slot >= region.z) {  // (the early phase reserved a late cluster draw: never, but counted)
        atomicAdd(stats[STAT_DRAW_OVERFLOW], 1u);
      } else {
        if (sw) slot = region.z - 1u - slot;
        draws[region.y + slot] = DrawCommand(3u * clusterTriangles, 1u, firstIndex, vertexOffset, id);
      }
    }
  }
}
