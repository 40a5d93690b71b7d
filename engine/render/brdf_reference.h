// Double-precision CPU twin of shaders/lighting.glsl's shadeSurface(): the glTF 2.0 metallic-roughness BRDF
// (specification appendix B: GGX D, Smith height-correlated V, Schlick F, Lambert diffuse of (1 - F) c_diff),
// the scene's directional light, KHR_lights_punctual point and spot lights with the range window (spot: times the
// extension's cone attenuation) and directional lights, the ambient term
// AMBIENT_RADIANCE x (c_diff + f0) x occlusion, and emissive; KHR_materials_clearcoat layered over all of it
// (the extension's fresnel_coat: base x (1 - clearcoat x Fc(n_c.v)) + clearcoat x the coat's f0 0.04 GGX lobe,
// with Fc of the ambient light as the coat's ambient reflection), KHR_materials_unlit (the base colour as is), and
// the KHR_materials_pbrSpecularGlossiness BRDF evaluated directly (c_diff = diffuse (1 - max(specular)), f0 =
// specular: what the importer's conversion to metallic-roughness is measured against). Independent code (written
// from the specifications, not generated from the shader), for the GPU tests' per-pixel comparison.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "visbuf/scene/scene.h"

namespace visbuf {

struct SurfaceReference {
  glm::dvec3 position{0.0};  // camera-relative world position (camera at the origin)
  glm::dvec3 normal{0.0, 1.0, 0.0};  // unit
  glm::dvec3 baseColor{1.0};
  double metallic = 0.0, roughness = 1.0, occlusion = 1.0;
  glm::dvec3 emissive{0.0};
  // Unit vector towards the eye; 0: -normalize(position) (perspective). An orthographic view's is the opposite of
  // its view direction everywhere.
  glm::dvec3 towardsEye{0.0};
  bool unlit = false;                        // the colour is baseColor
  double clearcoat = 0.0;                    // coat weight, 0: none
  double clearcoatRoughness = 0.0;
  glm::dvec3 clearcoatNormal{0.0, 1.0, 0.0};  // unit
  // The specular-glossiness model instead of metallic-roughness: baseColor is the diffuse colour, `specular` the
  // f0, roughness 1 - glossiness; metallic unused.
  bool specularGlossiness = false;
  glm::dvec3 specular{0.04};
};

// glTF BRDF x n.l for unit normal n, view v and light l directions (0 when n.l <= 0).
glm::dvec3 brdfCosineReference(const SurfaceReference& s, const glm::dvec3& v, const glm::dvec3& l);

// Outgoing radiance towards the camera: every light of `scene` (directional: scene.lightDirection and
// lightIntensity; every KHR_lights_punctual light of scene.pointLights, positions made camera-relative with
// `cameraPosition`).
glm::dvec3 shadeReference(const SurfaceReference& s, const Scene& scene, const glm::dvec3& cameraPosition);

}  // namespace visbuf
