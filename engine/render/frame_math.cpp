#include "visbuf/render/frame_math.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace visbuf {

FrameMath computeFrameMath(const Camera& camera, uint32_t width, uint32_t height) {
  FrameMath m;
  m.width = width;
  m.height = height;
  m.view = glm::lookAtRH(glm::dvec3(0.0), camera.target - camera.position, camera.up);
  const double f = 1.0 / std::tan(camera.fovY * 0.5);
  const double aspect = double(width) / double(height);
  glm::dmat4 p(0.0);
  p[0][0] = f / aspect;
  p[1][1] = -f;                 // Vulkan: +y down in framebuffer space
  p[3][2] = camera.nearPlane;   // z_clip = near
  p[2][3] = -1.0;               // w_clip = -z_view; depth = near / distance (1 at near, 0 at infinity)
  m.proj = p;
  m.viewProj = p * m.view;
  const glm::dmat4 t = glm::transpose(m.viewProj);  // rows of viewProj as columns of t
  const glm::dvec4 r0 = t[0], r1 = t[1], r2 = t[2], r3 = t[3];
  m.planes = {r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 - r2};
  for (auto& pl : m.planes) pl /= glm::length(glm::dvec3(pl));
  m.lodScale = double(height) * 0.5 * f;
  return m;
}

double sphereFrustumDistance(const FrameMath& math, const Camera& camera, glm::dvec3 centerWorld, double radius) {
  glm::dvec3 c = centerWorld - camera.position;
  double worst = -INFINITY;
  for (const auto& pl : math.planes) worst = std::max(worst, -(glm::dot(glm::dvec3(pl), c) + pl.w + radius));
  return worst;
}

bool sphereInFrustum(const FrameMath& math, const Camera& camera, glm::dvec3 centerWorld, double radius) {
  return sphereFrustumDistance(math, camera, centerWorld, radius) <= 0.0;
}

uint32_t selectLod(const Mesh& mesh, double maxScale, double dist, const FrameMath& math, double nearPlane,
                   float lodErrorPixels) {
  if (lodErrorPixels <= 0.0f || dist <= nearPlane) return 0;
  for (size_t l = mesh.lods.size() - 1; l > 0; --l)
    if (double(mesh.lods[l].error) * maxScale * math.lodScale <= double(lodErrorPixels) * dist) return uint32_t(l);
  return 0;
}

}  // namespace visbuf
