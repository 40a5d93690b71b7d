#version 460
// The late phase's frustum sieve (occlusion culling; config.h CULL_LATE_LISTED): one thread per object. A hidden
// object or one outside the frustum is decided here -- its history is cleared (the late cull would clear it: it is
// not visible now) and the frustum-culled are counted --, every other one is listed for the late cull proper, which
// then runs one thread per listed object. Its own pipeline: lavapipe runs a shader's every branch under a lane
// mask, so the late cull's pyramid, LOD and routing code cost the objects outside the frustum as much as the others.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "cull_tests.glsl"

void main() {
  uint id = gl_GlobalInvocationID.x;
  bool inside = false;
  uint frustumCulled = 0u;
  if (id < frame.objectCount) {
    ObjectData o = objectAt(id);
    if ((o.flags & OBJECT_FLAG_HIDDEN) == 0u) {
      vec4 sphere = meshBoundsSphere(o.meshIndex);
      inside = frustumVisible(objectToCamera(o, sphere.xyz), sphere.w * o.maxScale);
      frustumCulled = inside ? 0u : 1u;
    }
    if (!inside) history[id] = 0u;
  }
  appendToList(LATE_LIST_WORD(frame.objectCount), inside, id);
  uint culledSum = subgroupAdd(frustumCulled);
  if (subgroupElect() && culledSum > 0u) atomicAdd(stats[STAT_FRUSTUM_CULLED], culledSum);
}
