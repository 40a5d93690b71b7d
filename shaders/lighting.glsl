// The one lighting function of every path (visibility-buffer shading, forward reference, G-buffer
// baseline): what a surface point is (Surface, filled from the material and its textures by each path in
// the same way) and the light it returns towards the camera.
//
// BRDF: glTF 2.0 metallic-roughness (glTF 2.0 specification, appendix B): Trowbridge-Reitz/GGX D, Smith
// height-correlated visibility V, Schlick Fresnel F, Lambertian diffuse (1 - F) c_diff / pi, alpha =
// roughness^2. Lights: the scene's directional light (FrameData.lightDir: direction towards the light,
// intensity in w) and KHR_lights_punctual point and spot lights (inverse-square falloff windowed to zero at the
// range; spot: times the cone attenuation) and directional lights (engine/scene/light.h). Plus a uniform
// ambient environment AMBIENT_RADIANCE x (c_diff + f0), scaled by occlusion, and the emissive radiance.
// KHR_materials_clearcoat (specification's layering): every term of the base (lights, ambient, emissive) times
// 1 - clearcoat x Fc, with Fc = Schlick(f0 0.04, n_c.v), plus clearcoat x the coat's GGX specular lobe (f0 0.04, its
// own roughness and normal n_c) per light and clearcoat x Fc x AMBIENT_RADIANCE x occlusion of ambient.
// KHR_materials_unlit: the base colour is returned as is.
// engine/render/brdf_reference.cpp is the double-precision CPU twin the tests compare with.
#ifndef VISBUF_LIGHTING_GLSL
#define VISBUF_LIGHTING_GLSL

#include "common.glsl"
#include "shared/bindings_lighting.h"
#include "uniform_branch.glsl"

// Point lights; none bound are read when FrameData.pointLightCount is 0 (a scene with no point lights binds
// a placeholder: renderer.cpp).
layout(std430, set = 1, binding = LIGHTING_BINDING_LIGHTS) readonly buffer PointLightBlock { PointLightData pointLights[]; };
// Per 16x16 tile: the point lights that can reach a covered pixel of the tile (light_cull.comp.glsl).
layout(std430, set = 1, binding = LIGHTING_BINDING_LIGHT_TILES) readonly buffer LightTileBlock { uint lightTiles[]; };

struct Surface {
  vec3 position;   // camera-relative world position (the camera is at the origin)
  vec3 normal;     // unit world normal after normal mapping (flipped towards the viewer when double-sided)
  vec3 baseColor;  // linear RGB: material factor x texture x vertex colour
  float alpha;
  float metallic;  // [0,1]
  float roughness; // [0,1] (perceptual)
  float occlusion; // [0,1], 1: unoccluded (already lerped by the material's occlusion strength)
  vec3 emissive;   // linear RGB radiance added as is
  bool unlit;                // KHR_materials_unlit: the colour is baseColor
  float clearcoat;           // KHR_materials_clearcoat weight [0,1], 0: no coat
  float clearcoatRoughness;  // [0,1] (perceptual)
  vec3 clearcoatNormal;      // unit world normal of the coat (flipped as `normal` is)
};

// A surface with only a base colour and a normal (everything else at the glTF defaults of a plain
// material: dielectric, fully rough, unoccluded, not emissive, lit, no coat).
Surface plainSurface(vec3 position, vec3 normal, vec3 baseColor) {
  return Surface(position, normal, baseColor, 1.0, 0.0, 1.0, 1.0, vec3(0.0), false, 0.0, 0.0, normal);
}

// Whether the pipeline may meet the feature (VB_MATERIAL_FEATURES) and the surface has it.
bool surfaceUnlit(Surface s) { return (VB_MATERIAL_FEATURES & MATERIAL_FEATURE_UNLIT) != 0u && s.unlit; }
bool surfaceCoated(Surface s) { return (VB_MATERIAL_FEATURES & MATERIAL_FEATURE_CLEARCOAT) != 0u && s.clearcoat > 0.0; }

const float kPi = 3.14159265358979;

// GGX D x height-correlated Smith V (folded with 1 / (4 n.l n.v)) for a2 = alpha^2 = roughness^4.
float ggxDV(float ndoth, float ndotv, float ndotl, float a2) {
  float dDenom = ndoth * ndoth * (a2 - 1.0) + 1.0;
  float d = a2 / (kPi * dDenom * dDenom);
  float vis = 0.5 / (ndotl * sqrt(ndotv * ndotv * (1.0 - a2) + a2) + ndotv * sqrt(ndotl * ndotl * (1.0 - a2) + a2));
  return d * vis;
}

// The BRDF of glTF 2.0 appendix B times n.l: radiance reflected towards v per unit irradiance arriving along l
// (normal incidence). n, v, l unit vectors.
vec3 brdfCosine(Surface s, vec3 v, vec3 l) {
  float ndotl = dot(s.normal, l);
  if (ndotl <= 0.0) return vec3(0.0);
  vec3 h = normalize(l + v);
  // |n.v| (as Filament's shading does): an interpolated normal may face away from the camera at a visible pixel;
  // clamping n.v to ~0 there would make the height-correlated V a ratio of two tiny numbers (n.l / n.v).
  float ndotv = max(abs(dot(s.normal, v)), 1e-4);
  float ndoth = max(dot(s.normal, h), 0.0);
  float vdoth = max(dot(v, h), 0.0);
  vec3 cDiff = mix(s.baseColor, vec3(0.0), s.metallic);
  vec3 f0 = mix(vec3(0.04), s.baseColor, s.metallic);
  float alpha = s.roughness * s.roughness;
  float a2 = alpha * alpha;
  vec3 f = f0 + (vec3(1.0) - f0) * pow(1.0 - vdoth, 5.0);
  return ((vec3(1.0) - f) * cDiff / kPi + f * ggxDV(ndoth, ndotv, ndotl, a2)) * ndotl;
}

// The coat's Fresnel towards the viewer, Schlick with f0 0.04 (ior 1.5) at |n_c.v|: what the coat reflects and
// takes from the base.
float coatFresnel(Surface s, vec3 v) {
  return 0.04 + 0.96 * pow(1.0 - min(abs(dot(s.clearcoatNormal, v)), 1.0), 5.0);
}

// The coat's specular lobe x n_c.l (no weight): GGX D, V, Schlick F with f0 0.04, the coat's roughness and normal.
float coatCosine(Surface s, vec3 v, vec3 l) {
  float ndotl = dot(s.clearcoatNormal, l);
  if (ndotl <= 0.0) return 0.0;
  vec3 h = normalize(l + v);
  float ndotv = max(abs(dot(s.clearcoatNormal, v)), 1e-4);
  float alpha = s.clearcoatRoughness * s.clearcoatRoughness;
  float f = 0.04 + 0.96 * pow(1.0 - max(dot(v, h), 0.0), 5.0);
  return f * ggxDV(max(dot(s.clearcoatNormal, h), 0.0), ndotv, ndotl, alpha * alpha) * ndotl;
}

// brdfCosine with the coat layered over it where the surface has one.
vec3 surfaceCosine(Surface s, vec3 v, vec3 l) {
  vec3 base = brdfCosine(s, v, l);
  if (!surfaceCoated(s)) return base;
  return base * (1.0 - s.clearcoat * coatFresnel(s, v)) + vec3(s.clearcoat * coatCosine(s, v, l));
}

// One KHR_lights_punctual light's reflected radiance. Point and spot lights: exactly zero beyond the light's
// range (the tiled lists rely on it); a spot light is the point light's radiance times the extension's smooth
// cone attenuation of cd = dot(direction, -l). Directional: illuminance along -direction, no falloff. The point
// light's arithmetic is its own branch, so adding the other types does not change a point light's rounding.
vec3 pointLightRadiance(Surface s, vec3 v, PointLightData light) {
  if (light.type == LIGHT_DIRECTIONAL)
    return surfaceCosine(s, v, -light.direction.xyz) * light.colorIntensity.rgb * light.colorIntensity.w;
  vec3 toLight = light.positionRange.xyz + frame.cameraOffset.xyz - s.position;
  float d2 = max(dot(toLight, toLight), 1e-12);
  float range = light.positionRange.w;
  float window = 1.0;
  if (range > 0.0) {
    float r = d2 / (range * range);  // (d / range)^2
    window = clamp(1.0 - r * r, 0.0, 1.0);
    window *= window;
    if (window <= 0.0) return vec3(0.0);
  }
  vec3 l = toLight * inversesqrt(d2);
  if (light.type == LIGHT_SPOT) {
    float cone = clamp(dot(light.direction.xyz, -l) * light.angleScale + light.angleOffset, 0.0, 1.0);
    window *= cone * cone;
    if (window <= 0.0) return vec3(0.0);
  }
  return surfaceCosine(s, v, l) * light.colorIntensity.rgb * (light.colorIntensity.w * window / d2);
}

// Ambient + directional + point lights + emissive. `pixel` is the pixel being shaded: when this frame built
// tile lists (FrameData.lightTilesX > 0, the visibility-buffer path) it loops over its tile's list, else over
// every light (the forward reference, and the all-lights comparison). Both loops visit lights in ascending
// index order, and a light missing from a tile contributes exactly zero there, so the sums are the same.
vec3 shadeSurface(Surface s, uvec2 pixel) {
  if (surfaceUnlit(s)) return s.baseColor;
  vec3 v = towardsEye(s.position);
  vec3 cDiff = mix(s.baseColor, vec3(0.0), s.metallic);
  vec3 f0 = mix(vec3(0.04), s.baseColor, s.metallic);
  vec3 color = AMBIENT_RADIANCE * (cDiff + f0) * s.occlusion;
  vec3 emissive = s.emissive;
  if (surfaceCoated(s)) {  // the base's ambient and emission under the coat, and the coat's ambient reflection
    float fc = s.clearcoat * coatFresnel(s, v);
    color = color * (1.0 - fc) + vec3(AMBIENT_RADIANCE * fc * s.occlusion);
    emissive *= 1.0 - fc;
  }
  color += surfaceCosine(s, v, frame.lightDir.xyz) * frame.lightDir.w;
  // (the light count and the tile grid's width through uniformBranch: a branch or a loop bound on them alone made
  // lavapipe recompile the shading pass at every bind)
  const uint lightCount = uniformBranch(frame.pointLightCount), tilesX = uniformBranch(frame.lightTilesX);
  if (VB_POINT_LIGHTS != 0u && lightCount > 0u) {
    if (tilesX > 0u) {
      uint tile = (pixel.y / LIGHT_TILE_SIZE) * tilesX + pixel.x / LIGHT_TILE_SIZE;
      uint base = LIGHT_TILE_HEADER + tile * LIGHT_TILE_STRIDE;
      uint n = lightTiles[base];
      for (uint i = 0u; i < n; ++i) color += pointLightRadiance(s, v, pointLights[lightTiles[base + 1u + i]]);
    } else {
      for (uint i = 0u; i < lightCount; ++i) color += pointLightRadiance(s, v, pointLights[i]);
    }
  }
  return color + emissive;
}

#endif
