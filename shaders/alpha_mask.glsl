// The alpha of a surface point for alpha testing (MASK) and blending (BLEND), shared by the masked visibility
// raster, the forward reference and the transparency pass, so the three make the same cut-out decision.
#ifndef VISBUF_ALPHA_MASK_GLSL
#define VISBUF_ALPHA_MASK_GLSL

#include "material.glsl"

// materialIndex: MaterialData index; uv0/uv1: TEXCOORD_0/1; d*dx, d*dy: their screen derivatives per pixel
// (dFdx/dFdy in a fragment shader); color: the interpolated vertex colour (COLOR_0, 1 without one).
// Base colour factor alpha x base colour texture alpha (sampled with these gradients) x vertex colour alpha:
// material.glsl's materialAlpha(), as the shading pass computes it.
float maskAlpha(uint materialIndex, vec2 uv0, vec2 uv1, vec2 duv0dx, vec2 duv0dy, vec2 duv1dx, vec2 duv1dy,
                vec4 color) {
  SurfaceInputs si;
  si.uv0 = uv0;
  si.uv1 = uv1;
  si.duv0dx = duv0dx;
  si.duv0dy = duv0dy;
  si.duv1dx = duv1dx;
  si.duv1dy = duv1dy;
  si.color = color;
  return materialAlpha(materialIndex, si);
}

// glTF MASK: a fragment is cut out when its alpha is below the material's cutoff (params.w).
bool maskCutsOut(uint materialIndex, float alpha) { return alpha < materials[materialIndex].params.w; }

#endif
