#version 460
// Forward reference path, fragment stage. Variants: WRITE_IDS (also the IDs), COUNT_OVERDRAW (debug),
// ALPHA_MASK (masked draw lists: the same cut-out as the masked visibility raster), TRANSPARENT (the
// transparency pass: premultiplied colour and alpha for blending, glTF BLEND).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_samplerless_texture_functions : require
#include "material.glsl"
#if ALPHA_MASK || TRANSPARENT
#include "alpha_mask.glsl"
#endif

layout(location = 0) in vec3 inNormal;
layout(location = 1) in vec4 inColor;
layout(location = 2) flat in uint inMaterial;
layout(location = 3) flat in uint inObject;
layout(location = 4) in vec3 inPosition;  // camera-relative world
layout(location = 5) in vec4 inUv;        // TEXCOORD_0, TEXCOORD_1
layout(location = 6) in vec4 inTangent;   // world xyz, w: bitangent sign (0: none)
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
  // The same material evaluation as the shading pass, with the hardware's screen derivatives.
  SurfaceInputs si;
  si.position = inPosition;
  si.normal = inNormal;
  si.tangent = inTangent;
  si.dpdx = dFdx(inPosition);
  si.dpdy = dFdy(inPosition);
  si.uv0 = inUv.xy;
  si.uv1 = inUv.zw;
  si.duv0dx = dFdx(inUv.xy);
  si.duv0dy = dFdy(inUv.xy);
  si.duv1dx = dFdx(inUv.zw);
  si.duv1dy = dFdy(inUv.zw);
  si.color = inColor;
  // Every pipeline's front face is counter-clockwise on screen (mirrored objects' lists cull the other side);
  // the glTF front face of a mirrored object is clockwise.
  si.frontFacing = gl_FrontFacing != ((objectAt(inObject).flags & OBJECT_FLAG_FLIP_WINDING) != 0u);
#if ALPHA_MASK || TRANSPARENT
  float alpha = maskAlpha(inMaterial, si.uv0, si.uv1, si.duv0dx, si.duv0dy, si.duv1dx, si.duv1dy, inColor);
#endif
#if ALPHA_MASK
  if (maskCutsOut(inMaterial, alpha)) discard;
#endif
#if COUNT_OVERDRAW
  imageAtomicAdd(overdraw, ivec2(gl_FragCoord.xy), 1u);
#endif
  vec3 lit = shadeSurface(evaluateMaterial(inMaterial, si), uvec2(gl_FragCoord.xy));
#if TRANSPARENT
  outColor = vec4(lit * alpha, alpha);  // premultiplied: blended with ONE, ONE_MINUS_SRC_ALPHA
#else
  outColor = vec4(lit, 1.0);
#endif
#if WRITE_IDS
  outId = uvec2(inObject + 1u, uint(gl_PrimitiveID));
#endif
}
