// Lights of a scene beyond its directional light: KHR_lights_punctual point, spot and directional lights, their
// validation, and a generator that scatters N point lights over a scene's objects.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/core/result.h"

namespace visbuf {

struct Scene;

enum class LightType : uint32_t { Point = 0, Spot = 1, Directional = 2 };  // == LIGHT_* in shaders/shared/config.h

// A KHR_lights_punctual light (the renderer's "point lights": every light besides the scene's own directional
// one, culled per screen tile). The type defaults to a point light.
//   Point: radiant intensity `intensity` (candela) x `color`, falling off as 1/d^2 windowed to exactly zero at
//     `range`: clamp(1 - (d/range)^4, 0, 1)^2 / d^2. range <= 0: infinite (no window; such a light is in every
//     screen tile's list).
//   Spot: a point light times the extension's smooth cone attenuation of cd = dot(direction, -l) (l: unit
//     vector from the surface to the light): clamp(cd * scale + offset, 0, 1)^2 with
//     scale = 1 / max(0.001, cos(innerConeAngle) - cos(outerConeAngle)), offset = -cos(outerConeAngle) * scale
//     (spotAngleScaleOffset()). Culled by its range sphere, like a point light.
//   Directional: illuminance `intensity` (lux) x `color` arriving along `direction` from infinitely far (no
//     falloff, no range: in every tile's list). `position` and `range` are unused.
struct PointLight {
  glm::dvec3 position{0.0};  // world
  glm::vec3 color{1.0f};     // linear RGB, each >= 0
  float intensity = 1.0f;    // >= 0
  float range = 0.0f;        // world units; <= 0: infinite
  LightType type = LightType::Point;
  glm::vec3 direction{0.0f, 0.0f, -1.0f};  // spot / directional: unit, world, the way the light shines (the
                                           // node's -Z)
  float innerConeAngle = 0.0f;             // spot: radians, 0 <= inner < outer <= pi/2
  float outerConeAngle = 0.78539816f;      // spot: radians (glTF's default pi/4)
};

// The spot cone's attenuation clamp(cd * scale + offset, 0, 1)^2 as (scale, offset), from the light's angles (the
// formula KHR_lights_punctual recommends), in double precision; (0, 1) for point and directional lights.
glm::dvec2 spotAngleScaleOffset(const PointLight& light);

// Finite positions, colours and intensities >= 0, finite range; spot and directional lights: a unit direction
// (|length - 1| <= 1e-3); spot lights: 0 <= innerConeAngle < outerConeAngle <= pi/2. A clear error naming the
// light otherwise.
Status validatePointLights(const std::vector<PointLight>& lights);

// Adds `count` point lights at seeded uniform positions inside the box of the scene's object bounds, each with a
// random saturated colour. Their range is 1.5x the mean spacing of the lights (so any point sees ~14 of them at
// any count), their intensity 0.5 x range^2 (a light at half its range gives irradiance ~1.8). No-op for 0.
void scatterPointLights(Scene& scene, uint32_t count, uint64_t seed);

}  // namespace visbuf
