#version 460
// The late phase's occlusion test (occlusion culling), one thread per listed object: variant CULL_LATE_LISTED over
// the objects the sieve (cull_sieve.comp) found inside the frustum, CULL_REFINE over those its coarse test left. It
// decides visibility only -- the history bit, the next frame's visible list, the refinement list and the counters --
// and lists the objects to draw late (visible now, not drawn early) for the late draw dispatch (cull.comp,
// CULL_LATE_DRAW), which selects their LOD and routes them. Its own pipeline: lavapipe runs a shader's every branch
// under a lane mask, so inside cull.comp each of the field view's 736,600 occluded kittens paid for the LOD
// selection, routing and draw-slot code of the few it draws late.
//
// An object of the list is inside the frustum and not hidden (the sieve decided the others), so the early phase drew
// it exactly when its history bit is set and its draw list is one (cull.comp's early condition).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "cull_tests.glsl"

void main() {
  const bool refine = pc.variant == CULL_REFINE;
  const uint refineList = VISIBLE_LIST_HEADER + frame.objectCount;
  const uint listBase = refine ? refineList : LATE_LIST_WORD(frame.objectCount);
  bool valid = gl_GlobalInvocationID.x < min(visibleList[listBase], frame.objectCount);
  uint id = valid ? visibleList[listBase + VISIBLE_LIST_HEADER + gl_GlobalInvocationID.x] : 0u;
  bool visibleNow = false, deferred = false, drawLate = false;
  uint occluded = 0u, subpixel = 0u;
  if (valid) {
    ObjectData o = objectAt(id);
    vec4 sphere = meshBoundsSphere(o.meshIndex);
    vec3 c = objectToCamera(o, sphere.xyz);
    vec3 v;
    float rr;
    vec2 lo, hi;
    bool rect = screenRect(c, sphere.w * o.maxScale, v, rr, lo, hi);
    uint test = occlusionTest(rect, v, rr, lo, hi, refine, true);
    deferred = test == 4u;  // to the refinement dispatch, which decides it
    if (!deferred) {
      occluded = test == 1u ? 1u : 0u;
      subpixel = test == 2u ? 1u : 0u;
      visibleNow = test == 0u;
      drawLate = visibleNow && history[id] == 0u && objectDrawList(o.flags) != DRAW_LIST_NONE;
      history[id] = visibleNow ? 1u : 0u;
    }
  }
  appendToList(0u, visibleNow, id);  // the next frame's early phase
  if (!refine) appendToList(refineList, deferred, id);
  appendToList(LATE_DRAW_LIST_WORD(frame.objectCount), drawLate, id);
  uint occludedSum = subgroupAdd(occluded);
  uint subpixelSum = subgroupAdd(subpixel);
  uint refinedSum = refine ? subgroupAdd(valid ? 1u : 0u) : 0u;
  if (subgroupElect()) {
    if (refinedSum > 0u) atomicAdd(stats[STAT_REFINE_TESTED], refinedSum);
    if (refine && occludedSum > 0u) atomicAdd(stats[STAT_REFINE_OCCLUDED], occludedSum);
    if (subpixelSum > 0u) atomicAdd(stats[STAT_SUBPIXEL_CULLED], subpixelSum);
  }
}
