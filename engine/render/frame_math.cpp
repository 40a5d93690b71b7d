#include "visbuf/render/frame_math.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace visbuf {

ProjectionWindow projectionWindow(const Camera& camera, uint32_t width, uint32_t height) {
  const double viewport = double(width) / double(height);
  ProjectionWindow w;
  if (camera.projection == Projection::Orthographic) {
    w = {camera.xmag, camera.ymag};
  } else {
    w.halfY = std::tan(camera.fovY * 0.5);
    w.halfX = w.halfY * (camera.aspectRatio > 0.0 ? camera.aspectRatio : viewport);
  }
  // Fit the authored window inside the viewport: widen the axis where the viewport is relatively wider.
  if (w.halfX / w.halfY < viewport)
    w.halfX = w.halfY * viewport;
  else
    w.halfY = w.halfX / viewport;
  return w;
}

FrameMath computeFrameMath(const Camera& camera, uint32_t width, uint32_t height) {
  FrameMath m;
  m.width = width;
  m.height = height;
  m.forward = glm::normalize(camera.target - camera.position);
  m.view = glm::lookAtRH(glm::dvec3(0.0), camera.target - camera.position, camera.up);
  m.orthographic = camera.projection == Projection::Orthographic;
  const ProjectionWindow w = projectionWindow(camera, width, height);
  const double n = camera.nearPlane, f = camera.farPlane;
  glm::dmat4 p(0.0);
  p[0][0] = 1.0 / w.halfX;
  p[1][1] = -1.0 / w.halfY;  // Vulkan: +y down in framebuffer space
  if (m.orthographic) {
    p[2][2] = 1.0 / (f - n);  // depth = (f - d) / (f - n)
    p[3][2] = f / (f - n);
    p[3][3] = 1.0;
  } else {
    // depth = n (f - d) / (d (f - n)); infinite: n / d (1 at near, 0 at infinity)
    p[2][2] = std::isfinite(f) ? n / (f - n) : 0.0;
    p[3][2] = std::isfinite(f) ? n * f / (f - n) : n;
    p[2][3] = -1.0;  // w_clip = -z_view
  }
  m.proj = p;
  m.viewProj = p * m.view;
  const glm::dmat4 t = glm::transpose(m.viewProj);  // rows of viewProj as columns of t
  const glm::dvec4 r0 = t[0], r1 = t[1], r2 = t[2], r3 = t[3];
  const bool far = m.orthographic || std::isfinite(f);
  m.planes = {r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 - r2, far ? r2 : glm::dvec4(0.0, 0.0, 0.0, 1.0)};
  for (size_t i = 0; i < (far ? 6u : 5u); ++i) m.planes[i] /= glm::length(glm::dvec3(m.planes[i]));
  m.lodScale = double(height) * 0.5 / w.halfY;
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
  if (lodErrorPixels <= 0.0f) return 0;
  if (math.orthographic)
    dist = 1.0;
  else if (dist <= nearPlane)
    return 0;
  for (size_t l = mesh.lods.size() - 1; l > 0; --l)
    if (double(mesh.lods[l].error) * maxScale * math.lodScale <= double(lodErrorPixels) * dist) return uint32_t(l);
  return 0;
}

}  // namespace visbuf
