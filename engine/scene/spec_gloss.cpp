#include "visbuf/scene/spec_gloss.h"

#include <algorithm>
#include <cmath>

namespace visbuf {
namespace {

constexpr double kDielectricF0 = 0.04;

double brightness(const glm::dvec3& c) { return std::sqrt(0.299 * c.r * c.r + 0.587 * c.g * c.g + 0.114 * c.b * c.b); }

}  // namespace

MetalRough specGlossToMetalRough(const glm::dvec4& diffuseIn, const glm::dvec3& specularIn, double glossiness) {
  const glm::dvec4 diffuse = glm::clamp(diffuseIn, 0.0, 1.0);
  const glm::dvec3 specular = glm::clamp(specularIn, 0.0, 1.0);
  const double maxSpecular = std::max({specular.r, specular.g, specular.b});
  const glm::dvec3 cDiff = glm::dvec3(diffuse) * (1.0 - maxSpecular);
  const double d = brightness(cDiff), s = brightness(specular);
  double m = 0.0;
  if (s > kDielectricF0) {
    const double b = d + s - 2.0 * kDielectricF0, c = s - kDielectricF0;
    m = std::clamp((-b + std::sqrt(b * b + 4.0 * kDielectricF0 * c)) / (2.0 * kDielectricF0), 0.0, 1.0);
  }
  const glm::dvec3 fromDiffuse = cDiff / std::max(1.0 - m, 1e-6);
  const glm::dvec3 fromSpecular = (specular - kDielectricF0 * (1.0 - m)) / std::max(m, 1e-6);
  MetalRough out;
  out.baseColor = glm::dvec4(glm::clamp(glm::mix(fromDiffuse, fromSpecular, m * m), 0.0, 1.0), diffuse.a);
  out.metallic = m;
  out.roughness = 1.0 - std::clamp(glossiness, 0.0, 1.0);
  return out;
}

}  // namespace visbuf
