#version 460
// The late phase's frustum sieve (occlusion culling; config.h CULL_LATE_LISTED) over every object. A hidden
// object or one outside the frustum is decided here -- its history is cleared (the late cull would clear it: it is
// not visible now) and the frustum-culled are counted --, every other one is listed for the late cull proper, which
// then runs one thread per listed object. Its own pipeline: lavapipe runs a shader's every branch under a lane
// mask, so the late cull's pyramid, LOD and routing code cost the objects outside the frustum as much as the others.
// Each subgroup sieves SIEVE_OBJECTS_PER_THREAD x its size consecutive objects and takes their list entries with
// one atomic, and a second step (pc.material == 1, one thread) sizes the late cull's dispatch from the list's count:
// in a view from outside the scene the sieve lists most objects (the field view: 78 % of 1M kittens), and atomics on
// the words every core writes, two per subgroup of 8 objects, cost about as much as the list saved (lavapipe).
// A third step (pc.material == 2, one thread, after the late cull's tests) counts the objects they found occluded:
// every listed object was found visible (listed for the next frame), covering no pixel centre (counted) or
// occluded, so the count is the difference, and the late cull keeps no counter of its own for them (on lavapipe an
// atomic on a word both cores write, in nearly every subgroup of a field view: about 8 % of the late cull at 1M
// kittens).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "cull_tests.glsl"

void main() {
  if (pc.material == 1u) {  // the second step: the late cull's dispatch size
    uint base = LATE_LIST_WORD(frame.objectCount);
    if (gl_GlobalInvocationID.x == 0u)
      visibleList[base + 1u] = (min(visibleList[base], frame.objectCount) + CULL_WORKGROUP_SIZE - 1u) / CULL_WORKGROUP_SIZE;
    return;
  }
  if (pc.material == 2u) {  // the third step: the late cull's occluded objects
    if (gl_GlobalInvocationID.x == 0u) {
      uint tested = min(visibleList[LATE_LIST_WORD(frame.objectCount)], frame.objectCount);
      uint notOccluded = min(visibleList[0] + stats[STAT_SUBPIXEL_CULLED], tested);
      stats[STAT_OCCLUSION_CULLED] = tested - notOccluded;
    }
    return;
  }
  uint first = (gl_WorkGroupID.x * gl_NumSubgroups + gl_SubgroupID) * SIEVE_OBJECTS_PER_THREAD * gl_SubgroupSize;
  uvec4 ballots[SIEVE_OBJECTS_PER_THREAD];
  uint total = 0u, frustumCulled = 0u;
  for (uint k = 0u; k < SIEVE_OBJECTS_PER_THREAD; ++k) {
    uint id = first + k * gl_SubgroupSize + gl_SubgroupInvocationID;
    bool inside = false;
    if (id < frame.objectCount) {
      ObjectData o = objectAt(id);
      if ((o.flags & OBJECT_FLAG_HIDDEN) == 0u) {
        vec4 sphere = meshBoundsSphere(o.meshIndex);
        inside = frustumVisible(objectToCamera(o, sphere.xyz), sphere.w * o.maxScale);
        frustumCulled += inside ? 0u : 1u;
      }
      if (!inside) history[id] = 0u;
    }
    ballots[k] = subgroupBallot(inside);
    total += subgroupBallotBitCount(ballots[k]);
  }
  uint base = LATE_LIST_WORD(frame.objectCount);
  uint at = 0u;
  if (subgroupElect() && total > 0u) at = atomicAdd(visibleList[base], total);
  at = subgroupBroadcastFirst(at) + base + VISIBLE_LIST_HEADER;
  for (uint k = 0u; k < SIEVE_OBJECTS_PER_THREAD; ++k) {
    if (subgroupBallotBitExtract(ballots[k], gl_SubgroupInvocationID))
      visibleList[at + subgroupBallotExclusiveBitCount(ballots[k])] = first + k * gl_SubgroupSize + gl_SubgroupInvocationID;
    at += subgroupBallotBitCount(ballots[k]);
  }
  uint culledSum = subgroupAdd(frustumCulled);
  if (subgroupElect() && culledSum > 0u) atomicAdd(stats[STAT_FRUSTUM_CULLED], culledSum);
}
