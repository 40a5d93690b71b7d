#version 460
// G-buffer baseline, lighting: one thread per pixel reads the attribute targets and the depth, rebuilds the
// camera-relative position from the depth and lights the surface with the same shadeSurface() as every path.
// Background pixels (depth 0, reverse-Z) are skipped: the colour image was cleared to the background before.
#extension GL_GOOGLE_include_directive : require
#include "lighting.glsl"
#include "shared/bindings_gbuffer_lighting.h"

layout(local_size_x = SHADE_TILE_X, local_size_y = SHADE_TILE_Y) in;
layout(set = 1, binding = GBUFFER_LIGHTING_BINDING_TARGETS) uniform sampler2D gbuffer[GBUFFER_TARGETS];
layout(set = 1, binding = GBUFFER_LIGHTING_BINDING_DEPTH) uniform sampler2D gbufferDepth;
layout(set = 1, binding = GBUFFER_LIGHTING_BINDING_COLOR, rgba16f) uniform writeonly image2D colorOut;
#if WRITE_ATTRIBUTES
// Test variant: the rebuilt position and the depth in the attribute record's slots 0..3 (config.h), slot 7 = 1.
layout(std430, set = 1, binding = GBUFFER_LIGHTING_BINDING_ATTRIBUTES) writeonly buffer AttributeBlock { float attributes[]; };
#endif

// The pixel centre's camera-relative position at `depth` (common.glsl's inverse of the projection).
vec3 cameraRelativePosition(ivec2 p, float depth) {
  return cameraRelativeAt((vec2(p) + 0.5) * frame.viewport.zw * 2.0 - 1.0, depth);
}

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= int(frame.viewport.x) || p.y >= int(frame.viewport.y)) return;
  float depth = texelFetch(gbufferDepth, p, 0).x;
  if (depth <= 0.0) return;  // nothing drawn (cleared to 0 = the far plane)
  vec4 base = texelFetch(gbuffer[0], p, 0);      // sRGB decoded by the sampler: linear
  vec2 oct = texelFetch(gbuffer[1], p, 0).xy;
  vec4 material = texelFetch(gbuffer[2], p, 0);
  vec3 emissive = texelFetch(gbuffer[3], p, 0).rgb;
  Surface s;
  s.position = cameraRelativePosition(p, depth);
  s.normal = octDecode(packSnorm2x16(oct));
  s.baseColor = base.rgb;
  s.alpha = base.a;
  s.metallic = material.x;
  s.roughness = material.y;
  s.occlusion = material.z;
  s.emissive = emissive;
  s.unlit = material.w > 0.5;
  vec4 coat = (VB_MATERIAL_FEATURES & MATERIAL_FEATURE_CLEARCOAT) != 0u ? texelFetch(gbuffer[4], p, 0) : vec4(0.0);
  s.clearcoatNormal = octDecode(packSnorm2x16(coat.xy));
  s.clearcoatRoughness = coat.z;
  s.clearcoat = coat.w;
  imageStore(colorOut, p, vec4(shadeSurface(s, uvec2(p)), 1.0));
#if WRITE_ATTRIBUTES
  uint record = (uint(p.y) * uint(frame.viewport.x) + uint(p.x)) * ATTRIBUTE_FLOATS;
  attributes[record + 0u] = s.position.x;
  attributes[record + 1u] = s.position.y;
  attributes[record + 2u] = s.position.z;
  attributes[record + 3u] = depth;
  attributes[record + 7u] = 1.0;
#endif
}
