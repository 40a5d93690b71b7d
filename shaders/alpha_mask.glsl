// The alpha of a surface point for alpha testing (MASK) and blending (BLEND), shared by the masked visibility
// raster, the forward reference and the transparency pass, so the three make the same cut-out decision.
#ifndef VISBUF_ALPHA_MASK_GLSL
#define VISBUF_ALPHA_MASK_GLSL

#include "common.glsl"

// materialIndex: MaterialData index; uv0/uv1: TEXCOORD_0/1; d*dx, d*dy: their screen derivatives per pixel
// (dFdx/dFdy in a fragment shader); color: the interpolated vertex colour (COLOR_0, 1 without one).
// Today: base colour factor alpha x vertex colour alpha. Textured materials switch this body over to
// material.glsl's materialAlpha(), which takes exactly these arguments (base colour texture alpha sampled with
// the explicit gradients).
float maskAlpha(uint materialIndex, vec2 uv0, vec2 uv1, vec2 duv0dx, vec2 duv0dy, vec2 duv1dx, vec2 duv1dy,
                vec4 color) {
  return materials[materialIndex].baseColor.a * color.a;
}

// glTF MASK: a fragment is cut out when its alpha is below the material's cutoff (params.w).
bool maskCutsOut(uint materialIndex, float alpha) { return alpha < materials[materialIndex].params.w; }

#endif
