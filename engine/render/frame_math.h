// Camera math shared by the GPU frame constants, the forward path's CPU culling and the tests'
// double-precision references. Everything is camera-relative: the camera sits at the origin.
#pragma once

#include <array>
#include <cstdint>

#include <glm/glm.hpp>

#include "visbuf/scene/scene.h"

namespace visbuf {

struct FrameMath {
  glm::dmat4 view{1.0};      // rotation only (camera at the origin), right-handed, looking down -Z
  glm::dmat4 proj{1.0};      // reverse-Z, infinite far plane, Vulkan clip space (y down)
  glm::dmat4 viewProj{1.0};
  std::array<glm::dvec4, 5> planes{};  // left, right, bottom, top, near; unit normals, inside >= 0
  double lodScale = 1.0;     // pixels per unit at distance 1
  uint32_t width = 1, height = 1;
};

FrameMath computeFrameMath(const Camera& camera, uint32_t width, uint32_t height);

// Double-precision reference: does the sphere (world space) intersect the frustum?
bool sphereInFrustum(const FrameMath& math, const Camera& camera, glm::dvec3 centerWorld, double radius);
// Signed distance of the sphere to the frustum: max over planes of -(d + r); <= 0 means inside.
double sphereFrustumDistance(const FrameMath& math, const Camera& camera, glm::dvec3 centerWorld, double radius);

// LOD a CPU path would pick with the same rule as the cull shader (double precision).
uint32_t selectLod(const Mesh& mesh, double maxScale, double distanceToSphere, const FrameMath& math,
                   double nearPlane, float lodErrorPixels);

}  // namespace visbuf
