#version 460
// Forward reference path, fragment stage. Variants: WRITE_IDS (also the IDs), COUNT_OVERDRAW (debug),
// ALPHA_MASK (masked draw lists: the same cut-out as the masked visibility raster), TRANSPARENT (the
// transparency pass: premultiplied colour and alpha for blending, glTF BLEND).
#extension GL_GOOGLE_include_directive : require
#include "lighting.glsl"
#if ALPHA_MASK || TRANSPARENT
#include "alpha_mask.glsl"
#endif

layout(location = 0) in vec3 inNormal;
layout(location = 1) in vec4 inColor;
layout(location = 2) flat in uint inMaterial;
layout(location = 3) flat in uint inObject;
layout(location = 4) in vec3 inPosition;  // camera-relative world
layout(location = 5) in vec2 inUv0;
layout(location = 0) out vec4 outColor;
#if COUNT_OVERDRAW
#if !ALPHA_MASK
layout(early_fragment_tests) in;  // (not with discard: a cut-out fragment must not write depth)
#endif
layout(set = 0, binding = BINDING_OVERDRAW, r32ui) uniform coherent uimage2D overdraw;
#endif
#if WRITE_IDS
// Test/diagnostic variant: the same (object + 1, triangle) the visibility path decodes, so coverage can be
// compared pixel for pixel with the visibility buffer.
layout(location = 1) out uvec2 outId;
#endif

void main() {
#if ALPHA_MASK || TRANSPARENT
  // (TEXCOORD_1 is not interpolated yet: TEXCOORD_0 stands in, as in the masked visibility raster.)
  vec2 dx = dFdx(inUv0), dy = dFdy(inUv0);
  float alpha = maskAlpha(inMaterial, inUv0, inUv0, dx, dy, dx, dy, inColor);
#endif
#if ALPHA_MASK
  if (maskCutsOut(inMaterial, alpha)) discard;
#endif
#if COUNT_OVERDRAW
  imageAtomicAdd(overdraw, ivec2(gl_FragCoord.xy), 1u);
#endif
  vec4 baseColor = materials[inMaterial].baseColor * inColor;
  vec3 normal = normalize(inNormal);
  // Every pipeline's front face is counter-clockwise on screen (mirrored objects' lists cull the other side);
  // the glTF front face of a mirrored object is clockwise. Double-sided back faces shade with the flipped normal.
  bool front = gl_FrontFacing != ((objectAt(inObject).flags & OBJECT_FLAG_FLIP_WINDING) != 0u);
  if ((materials[inMaterial].flags & MATERIAL_FLAG_DOUBLE_SIDED) != 0u && !front) normal = -normal;
  vec3 lit = shadeSurface(plainSurface(inPosition, normal, baseColor.rgb), uvec2(gl_FragCoord.xy));
#if TRANSPARENT
  outColor = vec4(lit * alpha, alpha);  // premultiplied: blended with ONE, ONE_MINUS_SRC_ALPHA
#else
  outColor = vec4(lit, 1.0);
#endif
#if WRITE_IDS
  outId = uvec2(inObject + 1u, uint(gl_PrimitiveID));
#endif
}
