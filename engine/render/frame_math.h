// Camera math shared by the GPU frame constants, the forward path's CPU culling and the tests'
// double-precision references. Everything is camera-relative: the camera sits at the origin.
#pragma once

#include <array>
#include <cstdint>

#include <glm/glm.hpp>

#include "visbuf/scene/scene.h"

namespace visbuf {

// The projection's window after fitting the authored one into the viewport (scene.h, Camera): perspective: the
// tangents of the half angles; orthographic: the half extents in world units.
struct ProjectionWindow {
  double halfX = 1.0, halfY = 1.0;
};
ProjectionWindow projectionWindow(const Camera& camera, uint32_t width, uint32_t height);

struct FrameMath {
  glm::dmat4 view{1.0};      // rotation only (camera at the origin), right-handed, looking down -Z
  // Reverse-Z, Vulkan clip space (y down). Perspective: w_clip = -z_view, depth = proj[3][2] / d - proj[2][2]
  // for the view distance d = -z_view (proj[2][2] = 0: infinite far plane). Orthographic: w_clip = 1,
  // depth = proj[3][2] - proj[2][2] d. Either way 1 at the near plane, 0 at the far plane (or infinity).
  glm::dmat4 proj{1.0};
  glm::dmat4 viewProj{1.0};
  // left, right, bottom, top, near, far; unit normals, inside >= 0. Infinite far plane: far = (0, 0, 0, 1).
  std::array<glm::dvec4, 6> planes{};
  // Perspective: pixels per world unit at view distance 1 (a length L at distance d covers L lodScale / d pixels).
  // Orthographic: pixels per world unit at any distance.
  double lodScale = 1.0;
  bool orthographic = false;
  glm::dvec3 forward{0.0, 0.0, -1.0};  // unit world-space view direction
  uint32_t width = 1, height = 1;
};

FrameMath computeFrameMath(const Camera& camera, uint32_t width, uint32_t height);

// Double-precision reference: does the sphere (world space) intersect the frustum?
bool sphereInFrustum(const FrameMath& math, const Camera& camera, glm::dvec3 centerWorld, double radius);
// Signed distance of the sphere to the frustum: max over planes of -(d + r); <= 0 means inside.
double sphereFrustumDistance(const FrameMath& math, const Camera& camera, glm::dvec3 centerWorld, double radius);

// LOD a CPU path would pick with the same rule as the cull shader (double precision). Perspective: the coarsest
// level whose error * maxScale * lodScale <= lodErrorPixels * distanceToSphere (level 0 within the near plane);
// orthographic: error * maxScale * lodScale <= lodErrorPixels (the projected size does not depend on distance).
uint32_t selectLod(const Mesh& mesh, double maxScale, double distanceToSphere, const FrameMath& math,
                   double nearPlane, float lodErrorPixels);

}  // namespace visbuf
