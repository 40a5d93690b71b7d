#include "visbuf/render/brdf_reference.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "visbuf/shared/config.h"

namespace visbuf {

glm::dvec3 brdfCosineReference(const SurfaceReference& s, const glm::dvec3& v, const glm::dvec3& l) {
  const double nl = glm::dot(s.normal, l);
  if (nl <= 0.0) return glm::dvec3(0.0);
  const glm::dvec3 h = glm::normalize(l + v);
  const double nv = std::max(std::abs(glm::dot(s.normal, v)), 1e-4);  // |n.v|: see lighting.glsl
  const double nh = std::max(glm::dot(s.normal, h), 0.0);
  const double vh = std::max(glm::dot(v, h), 0.0);
  const glm::dvec3 cDiff = s.baseColor * (1.0 - s.metallic);
  const glm::dvec3 f0 = glm::dvec3(0.04) * (1.0 - s.metallic) + s.baseColor * s.metallic;
  const double alpha = s.roughness * s.roughness, a2 = alpha * alpha;
  const glm::dvec3 fresnel = f0 + (glm::dvec3(1.0) - f0) * std::pow(1.0 - vh, 5.0);
  // Trowbridge-Reitz: D = a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2).
  const double q = nh * nh * (a2 - 1.0) + 1.0;
  const double d = a2 / (std::numbers::pi * q * q);
  // Height-correlated Smith, folded with 1 / (4 n.l n.v): V = 0.5 / (n.l sqrt(n.v^2 (1-a^2) + a^2) + n.v sqrt(...)).
  const double vis = 0.5 / (nl * std::sqrt(nv * nv * (1.0 - a2) + a2) + nv * std::sqrt(nl * nl * (1.0 - a2) + a2));
  const glm::dvec3 diffuse = (glm::dvec3(1.0) - fresnel) * cDiff / std::numbers::pi;
  return (diffuse + fresnel * (d * vis)) * nl;
}

glm::dvec3 shadeReference(const SurfaceReference& s, const Scene& scene, const glm::dvec3& cameraPosition) {
  const glm::dvec3 v = s.towardsEye != glm::dvec3(0.0) ? s.towardsEye : -glm::normalize(s.position);
  const glm::dvec3 cDiff = s.baseColor * (1.0 - s.metallic);
  const glm::dvec3 f0 = glm::dvec3(0.04) * (1.0 - s.metallic) + s.baseColor * s.metallic;
  glm::dvec3 color = AMBIENT_RADIANCE * (cDiff + f0) * s.occlusion;
  color += brdfCosineReference(s, v, glm::normalize(glm::dvec3(scene.lightDirection))) * double(scene.lightIntensity);
  for (const PointLight& light : scene.pointLights) {
    if (light.type == LightType::Directional) {
      color += brdfCosineReference(s, v, -glm::normalize(glm::dvec3(light.direction))) * glm::dvec3(light.color) *
               double(light.intensity);
      continue;
    }
    const glm::dvec3 toLight = (light.position - cameraPosition) - s.position;
    const double dist = glm::length(toLight);
    double window = 1.0;
    if (light.range > 0.0f) {
      const double x = dist / double(light.range);
      window = std::clamp(1.0 - x * x * x * x, 0.0, 1.0);
      window *= window;
    }
    if (window <= 0.0 || dist <= 0.0) continue;
    if (light.type == LightType::Spot) {
      // KHR_lights_punctual's cone, from the angles (not through spotAngleScaleOffset, which feeds the GPU): cd
      // is the cosine between the spot's axis and the direction from the light to the surface.
      const double cosOuter = std::cos(double(light.outerConeAngle));
      const double scale = 1.0 / std::max(0.001, std::cos(double(light.innerConeAngle)) - cosOuter);
      const double cd = glm::dot(glm::normalize(glm::dvec3(light.direction)), -toLight / dist);
      const double cone = std::clamp(cd * scale - cosOuter * scale, 0.0, 1.0);
      window *= cone * cone;
    }
    color += brdfCosineReference(s, v, toLight / dist) * glm::dvec3(light.color) *
             (double(light.intensity) * window / (dist * dist));
  }
  return color + s.emissive;
}

}  // namespace visbuf
