// The public camera's checks and its pose from matrices (scene.h).
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "visbuf/scene/scene.h"

namespace visbuf {

namespace {
Status bad(const std::string& what) { return makeError(ErrorCode::InvalidArgument, "camera: " + what); }
bool finite3(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
}  // namespace

bool NamedCamera::operator==(const NamedCamera& o) const {
  const Camera &a = camera, &b = o.camera;
  return name == o.name && a.position == b.position && a.target == b.target && a.up == b.up &&
         a.projection == b.projection && a.fovY == b.fovY && a.nearPlane == b.nearPlane && a.farPlane == b.farPlane &&
         a.aspectRatio == b.aspectRatio && a.xmag == b.xmag && a.ymag == b.ymag;
}

Status validateCamera(const Camera& c) {
  if (!finite3(c.position) || !finite3(c.target) || !finite3(c.up)) return bad("non-finite position, target or up");
  const glm::dvec3 forward = c.target - c.position;
  if (!(glm::length(forward) > 0.0)) return bad("target must differ from position");
  if (!(glm::length(c.up) > 0.0) ||
      glm::length(glm::cross(glm::normalize(forward), glm::normalize(c.up))) < 1e-9)
    return bad("view direction is parallel to the up vector");
  const bool ortho = c.projection == Projection::Orthographic;
  if (!ortho && c.projection != Projection::Perspective) return bad("unknown projection");
  if (!std::isfinite(c.nearPlane) || (ortho ? c.nearPlane < 0.0 : c.nearPlane <= 0.0))
    return bad(fmt::format("near plane {} must be {} 0", c.nearPlane, ortho ? ">=" : ">"));
  if (std::isnan(c.farPlane) || !(c.farPlane > c.nearPlane))
    return bad(fmt::format("far plane {} must be beyond the near plane {}", c.farPlane, c.nearPlane));
  if (ortho) {
    if (!std::isfinite(c.farPlane)) return bad("an orthographic camera needs a finite far plane");
    if (!(c.xmag > 0.0 && std::isfinite(c.xmag)) || !(c.ymag > 0.0 && std::isfinite(c.ymag)))
      return bad(fmt::format("orthographic xmag {} / ymag {} must be finite and > 0", c.xmag, c.ymag));
  } else {
    if (!(c.fovY > 0.0 && c.fovY < std::numbers::pi))
      return bad(fmt::format("vertical field of view {} rad must be in (0, pi)", c.fovY));
    if (!(c.aspectRatio >= 0.0 && std::isfinite(c.aspectRatio)))
      return bad(fmt::format("aspect ratio {} must be finite and > 0 (0: the viewport's)", c.aspectRatio));
  }
  return {};
}

Status setCameraPose(Camera& camera, const glm::dmat4& m) {
  const glm::dvec3 position(m[3]);
  glm::dvec3 back(m[2]), up(m[1]);  // +Z (the camera looks down -Z), +Y
  if (!finite3(position) || !finite3(back) || !finite3(up))
    return bad("pose matrix has a non-finite component");
  const double backLength = glm::length(back);
  if (!(backLength > 0.0)) return bad("pose matrix maps -Z to a zero direction");
  back /= backLength;
  up -= back * glm::dot(up, back);  // Gram-Schmidt: drops shear between the axes
  const double upLength = glm::length(up);
  if (!(upLength > 1e-12 * glm::length(glm::dvec3(m[1]))) || !(upLength > 0.0))
    return bad("pose matrix maps +Y onto the view direction (singular)");
  camera.position = position;
  camera.target = position - back;
  camera.up = up / upLength;
  return {};
}

Status setCameraView(Camera& camera, const glm::dmat4& worldToView) {
  const double det = glm::determinant(worldToView);
  if (!std::isfinite(det) || std::abs(det) < 1e-300) return bad("view matrix is singular or non-finite");
  return setCameraPose(camera, glm::inverse(worldToView));
}

}  // namespace visbuf
