// Branches on uniform values in compute shaders. lavapipe in Mesa 22 (Debian 12's) inlines push constants and
// uniform-buffer values into a shader with a branch that depends on such values alone, and because it keeps no
// variants it optimises, compiles and links that shader again at every bind and every push-constant change
// (measured on the micro-raster: 3.5 ms a bind at 1024x768, 170 ms with the shader cache off). A value read through a
// subgroup broadcast is the same value for a uniform operand, and no longer a uniform load to that analysis.
// Branches that can be selects are written as selects instead (sw_payload.glsl, visibility_id.glsl, common.glsl's
// projection functions). A loop bounded by a uniform value alone counts as such a branch. tests/cli_shader_variants.py
// renders every compute path with lavapipe's shader cache off and on: a pass that recompiles fails it.
// Compute shaders only (VB_COMPUTE_STAGE, set by shaders/CMakeLists.txt): in other stages the value is returned as
// it is (subgroup operations are not required there, and the raster stages showed no recompiles).
#ifndef VISBUF_UNIFORM_BRANCH_GLSL
#define VISBUF_UNIFORM_BRANCH_GLSL

#if defined(VB_COMPUTE_STAGE)
#extension GL_KHR_shader_subgroup_ballot : require
uint uniformBranch(uint v) { return subgroupBroadcastFirst(v); }
#else
uint uniformBranch(uint v) { return v; }
#endif

#endif
