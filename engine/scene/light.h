// Lights of a scene beyond its directional light: KHR_lights_punctual point lights, their validation, and a
// generator that scatters N of them over a scene's objects.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/core/result.h"

namespace visbuf {

struct Scene;

// A point light (glTF KHR_lights_punctual): radiant intensity `intensity` (candela) x `color`, falling off as
// 1/d^2 windowed to exactly zero at `range`: clamp(1 - (d/range)^4, 0, 1)^2 / d^2. range <= 0: infinite (no
// window; such a light is in every screen tile's list).
struct PointLight {
  glm::dvec3 position{0.0};  // world
  glm::vec3 color{1.0f};     // linear RGB, each >= 0
  float intensity = 1.0f;    // >= 0
  float range = 0.0f;        // world units; <= 0: infinite
};

// Finite positions, colours and intensities >= 0, finite range; a clear error naming the light otherwise.
Status validatePointLights(const std::vector<PointLight>& lights);

// Adds `count` point lights at seeded uniform positions inside the box of the scene's object bounds, each with a
// random saturated colour. Their range is 1.5x the mean spacing of the lights (so any point sees ~14 of them at
// any count), their intensity 0.5 x range^2 (a light at half its range gives irradiance ~1.8). No-op for 0.
void scatterPointLights(Scene& scene, uint32_t count, uint64_t seed);

}  // namespace visbuf
