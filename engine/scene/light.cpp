#include "visbuf/scene/light.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "visbuf/scene/generate.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

Status validatePointLights(const std::vector<PointLight>& lights) {
  for (size_t i = 0; i < lights.size(); ++i) {
    const PointLight& l = lights[i];
    const bool finite = std::isfinite(l.position.x) && std::isfinite(l.position.y) && std::isfinite(l.position.z) &&
                        std::isfinite(l.intensity) && std::isfinite(l.range) && std::isfinite(l.color.r) &&
                        std::isfinite(l.color.g) && std::isfinite(l.color.b);
    if (!finite) return makeError(ErrorCode::MalformedInput, fmt::format("point light {}: non-finite value", i));
    if (l.intensity < 0.0f || l.color.r < 0.0f || l.color.g < 0.0f || l.color.b < 0.0f)
      return makeError(ErrorCode::MalformedInput, fmt::format("point light {}: negative intensity or colour", i));
    if (l.type != LightType::Point && l.type != LightType::Spot && l.type != LightType::Directional)
      return makeError(ErrorCode::MalformedInput, fmt::format("light {}: unknown type {}", i, uint32_t(l.type)));
    if (l.type == LightType::Point) continue;
    const double len = glm::length(glm::dvec3(l.direction));
    if (!(std::abs(len - 1.0) <= 1e-3))
      return makeError(ErrorCode::MalformedInput,
                       fmt::format("{} light {}: direction ({}, {}, {}) is not a unit vector",
                                   l.type == LightType::Spot ? "spot" : "directional", i, l.direction.x,
                                   l.direction.y, l.direction.z));
    if (l.type != LightType::Spot) continue;
    // The extension's bounds; inner == outer would make the cone's edge a step (scale 1 / 0.001 hides it).
    if (!(l.innerConeAngle >= 0.0f && l.innerConeAngle < l.outerConeAngle &&
          double(l.outerConeAngle) <= std::numbers::pi / 2 + 1e-6))
      return makeError(ErrorCode::MalformedInput,
                       fmt::format("spot light {}: cone angles inner {} / outer {} (need 0 <= inner < outer <= pi/2)",
                                   i, l.innerConeAngle, l.outerConeAngle));
  }
  return {};
}

glm::dvec2 spotAngleScaleOffset(const PointLight& light) {
  if (light.type != LightType::Spot) return {0.0, 1.0};
  const double cosOuter = std::cos(double(light.outerConeAngle));
  const double scale = 1.0 / std::max(0.001, std::cos(double(light.innerConeAngle)) - cosOuter);
  return {scale, -cosOuter * scale};
}

void scatterPointLights(Scene& scene, uint32_t count, uint64_t seed) {
  if (count == 0) return;
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const Object& o : scene.objects) {
    const glm::dvec4 s = objectBoundsWorld(scene, o);
    lo = glm::min(lo, glm::dvec3(s) - s.w);
    hi = glm::max(hi, glm::dvec3(s) + s.w);
  }
  if (scene.objects.empty()) lo = hi = glm::dvec3(0.0);
  const glm::dvec3 size = glm::max(hi - lo, glm::dvec3(1e-3));
  const double spacing = std::cbrt(size.x * size.y * size.z / count);
  const float range = float(1.5 * spacing);
  Rng rng(seed * 7919 + 17);
  scene.pointLights.reserve(scene.pointLights.size() + count);
  for (uint32_t i = 0; i < count; ++i) {
    PointLight l;
    l.position = lo + glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()) * size;
    // A saturated hue: one channel full, one off, one random.
    const double h = rng.uniform() * 6.0;
    const int k = int(h);
    const float f = float(h - k);
    const glm::vec3 hues[6] = {{1, f, 0}, {1 - f, 1, 0}, {0, 1, f}, {0, 1 - f, 1}, {f, 0, 1}, {1, 0, 1 - f}};
    l.color = hues[std::min(k, 5)];
    l.range = range;
    l.intensity = 0.5f * range * range;
    scene.pointLights.push_back(l);
  }
}

}  // namespace visbuf
