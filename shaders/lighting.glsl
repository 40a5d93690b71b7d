// The one lighting function of every path (visibility-buffer shading, forward reference, G-buffer
// baseline): what a surface point is (Surface, filled from the material and its textures by each path in
// the same way) and the light it returns towards the camera.
#ifndef VISBUF_LIGHTING_GLSL
#define VISBUF_LIGHTING_GLSL

#include "common.glsl"

struct Surface {
  vec3 position;   // camera-relative world position (the camera is at the origin)
  vec3 normal;     // unit world normal after normal mapping (flipped towards the viewer when double-sided)
  vec3 baseColor;  // linear RGB: material factor x texture x vertex colour
  float alpha;
  float metallic;  // [0,1]
  float roughness; // [0,1] (perceptual)
  float occlusion; // [0,1], 1: unoccluded (already lerped by the material's occlusion strength)
  vec3 emissive;   // linear RGB radiance added as is
};

// A surface with only a base colour and a normal (everything else at the glTF defaults of a plain
// material: dielectric, fully rough, unoccluded, not emissive).
Surface plainSurface(vec3 position, vec3 normal, vec3 baseColor) {
  return Surface(position, normal, baseColor, 1.0, 0.0, 1.0, 1.0, vec3(0.0));
}

// Ambient + Lambert from the scene's directional light. `pixel` is the pixel being shaded (for
// screen-tiled light lists).
vec3 shadeSurface(Surface s, uvec2 pixel) {
  float ndotl = max(dot(s.normal, frame.lightDir.xyz), 0.0);
  return s.baseColor * (0.15 + frame.lightDir.w * ndotl) * s.occlusion + s.emissive;
}

#endif
