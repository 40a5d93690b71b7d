// Branches on uniform values in compute shaders. lavapipe in Mesa 22 (Debian 12's) inlines push constants and
// uniform-buffer values into a shader with a branch that depends on such values alone, and because it keeps no
// variants it optimises, compiles and links that shader again at every bind and every push-constant change
// (measured on the micro-raster: 3.5 ms a bind at 1024x768, 170 ms with the shader cache off). A value read through a
// subgroup broadcast is the same value for a uniform operand, and no longer a uniform load to that analysis.
// Branches that can be selects are written as selects instead (sw_payload.glsl, visibility_id.glsl).
#ifndef VISBUF_UNIFORM_BRANCH_GLSL
#define VISBUF_UNIFORM_BRANCH_GLSL

#extension GL_KHR_shader_subgroup_ballot : require

uint uniformBranch(uint v) { return subgroupBroadcastFirst(v); }

#endif
