#include "visbuf/render/brdf_reference.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "visbuf/shared/config.h"

namespace visbuf {
namespace {

// Schlick's Fresnel for reflectance f0 at cosine c.
glm::dvec3 schlick(const glm::dvec3& f0, double c) { return f0 + (glm::dvec3(1.0) - f0) * std::pow(1.0 - c, 5.0); }

// The specular microfacet term without Fresnel, D x V / (4 n.l n.v) for unit n, v, l, the half vector h and
// perceptual roughness r: Trowbridge-Reitz D = a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2) with a = r^2, and the
// height-correlated Smith visibility V = 0.5 / (n.l sqrt(n.v^2 (1-a^2) + a^2) + n.v sqrt(n.l^2 (1-a^2) + a^2)).
double microfacet(double nl, double nv, double nh, double roughness) {
  const double alpha = roughness * roughness, a2 = alpha * alpha;
  const double q = nh * nh * (a2 - 1.0) + 1.0;
  const double d = a2 / (std::numbers::pi * q * q);
  const double vis = 0.5 / (nl * std::sqrt(nv * nv * (1.0 - a2) + a2) + nv * std::sqrt(nl * nl * (1.0 - a2) + a2));
  return d * vis;
}

// The diffuse colour and the specular reflectance at normal incidence of the surface's model.
void lobeColors(const SurfaceReference& s, glm::dvec3& cDiff, glm::dvec3& f0) {
  if (s.specularGlossiness) {  // KHR_materials_pbrSpecularGlossiness: baseColor is the diffuse colour
    cDiff = s.baseColor * (1.0 - std::max({s.specular.r, s.specular.g, s.specular.b}));
    f0 = s.specular;
    return;
  }
  cDiff = s.baseColor * (1.0 - s.metallic);
  f0 = glm::dvec3(0.04) * (1.0 - s.metallic) + s.baseColor * s.metallic;
}

// The coat's Fresnel towards the viewer: f0 0.04 (ior 1.5) at |n_c.v|.
double coatFresnel(const SurfaceReference& s, const glm::dvec3& v) {
  return schlick(glm::dvec3(0.04), std::min(std::abs(glm::dot(s.clearcoatNormal, v)), 1.0)).x;
}

}  // namespace

glm::dvec3 brdfCosineReference(const SurfaceReference& s, const glm::dvec3& v, const glm::dvec3& l) {
  glm::dvec3 base(0.0);
  const double nl = glm::dot(s.normal, l);
  if (nl > 0.0) {
    const glm::dvec3 h = glm::normalize(l + v);
    const double nv = std::max(std::abs(glm::dot(s.normal, v)), 1e-4);  // |n.v|: see lighting.glsl
    const double nh = std::max(glm::dot(s.normal, h), 0.0);
    glm::dvec3 cDiff, f0;
    lobeColors(s, cDiff, f0);
    const glm::dvec3 fresnel = schlick(f0, std::max(glm::dot(v, h), 0.0));
    base = ((glm::dvec3(1.0) - fresnel) * cDiff / std::numbers::pi + fresnel * microfacet(nl, nv, nh, s.roughness)) * nl;
  }
  if (s.clearcoat <= 0.0) return base;
  // KHR_materials_clearcoat: the base attenuated by what the coat reflects, plus the coat's own specular lobe.
  double coat = 0.0;
  const double cl = glm::dot(s.clearcoatNormal, l);
  if (cl > 0.0) {
    const glm::dvec3 h = glm::normalize(l + v);
    const double cv = std::max(std::abs(glm::dot(s.clearcoatNormal, v)), 1e-4);
    const double ch = std::max(glm::dot(s.clearcoatNormal, h), 0.0);
    coat = schlick(glm::dvec3(0.04), std::max(glm::dot(v, h), 0.0)).x * microfacet(cl, cv, ch, s.clearcoatRoughness) * cl;
  }
  return base * (1.0 - s.clearcoat * coatFresnel(s, v)) + glm::dvec3(s.clearcoat * coat);
}

glm::dvec3 shadeReference(const SurfaceReference& s, const Scene& scene, const glm::dvec3& cameraPosition) {
  if (s.unlit) return s.baseColor;
  const glm::dvec3 v = s.towardsEye != glm::dvec3(0.0) ? s.towardsEye : -glm::normalize(s.position);
  glm::dvec3 cDiff, f0;
  lobeColors(s, cDiff, f0);
  glm::dvec3 color = AMBIENT_RADIANCE * (cDiff + f0) * s.occlusion;
  glm::dvec3 emissive = s.emissive;
  if (s.clearcoat > 0.0) {  // ambient and emission under the coat; the coat reflects Fc of the ambient light
    const double fc = s.clearcoat * coatFresnel(s, v);
    color = color * (1.0 - fc) + glm::dvec3(AMBIENT_RADIANCE * fc * s.occlusion);
    emissive *= 1.0 - fc;
  }
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
  return color + emissive;
}

}  // namespace visbuf
