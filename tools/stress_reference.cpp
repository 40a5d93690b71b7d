#include "stress_reference.h"

#include <algorithm>
#include <cmath>

#include "visbuf/render/pixel_judge.h"
#include "visbuf/shared/config.h"

namespace visbuf::tools {

namespace {

// acc = max(acc, v), where a NaN counts as an unbounded error (std::max would drop it).
void worst(double& acc, double v) { acc = std::isnan(v) ? INFINITY : std::max(acc, v); }

}  // namespace

std::optional<PixelReference> referenceAtPixel(const Scene& scene, const Camera& camera, const FrameMath& math,
                                               uint32_t x, uint32_t y, uint32_t object, uint32_t triangle) {
  const Object& o = scene.objects[object];
  const Mesh& mesh = scene.meshes[o.mesh];
  glm::dvec3 v[3];
  const gpu::Vertex* vert[3];
  for (int k = 0; k < 3; ++k) {
    vert[k] = &mesh.vertices[mesh.indices[mesh.lods[0].firstIndex + 3 * triangle + uint32_t(k)]];
    const glm::dvec4 world = o.transform * glm::dvec4(vert[k]->px, vert[k]->py, vert[k]->pz, 1.0);
    v[k] = glm::dvec3(world) - camera.position;
  }
  const double cx = x + 0.5, cy = y + 0.5;
  auto hit = intersectTriangle(v, pixelRay(math, cx, cy));
  if (!hit) return std::nullopt;
  PixelReference r;
  r.lambda = hit->second;
  r.faceNormal = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
  r.position = pixelRay(math, cx, cy).at(hit->first);
  const glm::dvec4 clip = math.viewProj * glm::dvec4(r.position, 1.0);
  r.depth = clip.z / clip.w;
  glm::dvec3 n(0.0);
  for (int k = 0; k < 3; ++k) {
    n += r.lambda[k] * glm::dvec3(octDecode(vert[k]->normal));
    r.uv += r.lambda[k] * glm::dvec2(vert[k]->u, vert[k]->v);
  }
  r.normal = glm::normalize(glm::transpose(glm::inverse(glm::dmat3(o.transform))) * n);
  const double h = 1e-3;  // pixels; lambda is smooth at this scale, the difference quotient exact to ~1e-9
  auto lambdaAt = [&](double px, double py) {
    auto s = intersectTriangle(v, pixelRay(math, px, py));
    return s ? s->second : glm::dvec3(NAN);
  };
  r.ddx = (lambdaAt(cx + h, cy) - lambdaAt(cx - h, cy)) / (2.0 * h);
  r.ddy = (lambdaAt(cx, cy + h) - lambdaAt(cx, cy - h)) / (2.0 * h);
  return r;
}

void AttributeErrors::merge(const AttributeErrors& o) {
  pixels += o.pixels;
  positionPixels = std::max(positionPixels, o.positionPixels);
  offSurface = std::max(offSurface, o.offSurface);
  lambdaPixels = std::max(lambdaPixels, o.lambdaPixels);
  edgeOnPixels += o.edgeOnPixels;
  derivativeEdgeOn = std::max(derivativeEdgeOn, o.derivativeEdgeOn);
  position = std::max(position, o.position);
  depth = std::max(depth, o.depth);
  normal = std::max(normal, o.normal);
  uv = std::max(uv, o.uv);
  lambda = std::max(lambda, o.lambda);
  derivative = std::max(derivative, o.derivative);
}

nlohmann::ordered_json AttributeErrors::toJson() const {
  return {{"pixels", pixels},
          {"position_px", positionPixels},
          {"off_surface_rel", offSurface},
          {"lambda_px", lambdaPixels},
          {"derivative_rel", derivative},
          {"edge_on_pixels", edgeOnPixels},
          {"derivative_rel_edge_on", derivativeEdgeOn},
          {"position_rel", position},
          {"depth_rel", depth},
          {"normal", normal},
          {"uv", uv},
          {"lambda", lambda}};
}

AttributeErrors compareAttributes(const Scene& scene, const Camera& camera, const FrameResult& frame,
                                  size_t stride) {
  const FrameMath math = computeFrameMath(camera, frame.width, frame.height);
  AttributeErrors e;
  const size_t pixels = size_t(frame.width) * frame.height;
  for (size_t i = 0; i < pixels; i += stride) {
    const uint32_t object = frame.ids[2 * i];
    if (object == 0 || object == 0xFFFFFFFFu) continue;
    const uint32_t x = uint32_t(i % frame.width), y = uint32_t(i / frame.width);
    auto ref = referenceAtPixel(scene, camera, math, x, y, object - 1, frame.ids[2 * i + 1]);
    const float* a = &frame.attributes[i * ATTRIBUTE_FLOATS];
    if (!ref || a[7] != 1.0f) {  // nothing written, or a ray parallel to the triangle: count as unbounded
      e.position = e.depth = e.normal = e.uv = e.lambda = e.derivative = INFINITY;
      continue;
    }
    ++e.pixels;
    const glm::dvec3 p(a[0], a[1], a[2]), n(a[4], a[5], a[6]);
    const glm::dvec4 clip = math.viewProj * glm::dvec4(p, 1.0);
    const glm::dvec2 pixel((clip.x / clip.w + 1.0) * 0.5 * frame.width, (clip.y / clip.w + 1.0) * 0.5 * frame.height);
    worst(e.positionPixels, glm::length(pixel - glm::dvec2(x + 0.5, y + 0.5)));
    worst(e.offSurface, std::abs(glm::dot(p - ref->position, ref->faceNormal)) / glm::length(ref->position));
    worst(e.position, glm::length(p - ref->position) / glm::length(ref->position));
    worst(e.depth, std::abs(a[3] - ref->depth) / ref->depth);
    worst(e.normal, glm::length(n - ref->normal));
    worst(e.uv, std::max(std::abs(a[8] - ref->uv.x), std::abs(a[9] - ref->uv.y)));
    worst(e.lambda, std::max(std::abs(a[10] - ref->lambda.y), std::abs(a[11] - ref->lambda.z)));
    {  // the barycentric error as the screen displacement that explains it: solve J delta = dlambda
      const double j11 = ref->ddx.y, j12 = ref->ddy.y, j21 = ref->ddx.z, j22 = ref->ddy.z;
      const double det = j11 * j22 - j12 * j21;
      const double l1 = a[10] - ref->lambda.y, l2 = a[11] - ref->lambda.z;
      worst(e.lambdaPixels, std::abs(det) > 0.0 ? glm::length(glm::dvec2(j22 * l1 - j12 * l2, j11 * l2 - j21 * l1)) /
                                                      std::abs(det)
                                                : INFINITY);
    }
    const double d[4] = {ref->ddx.y, ref->ddy.y, ref->ddx.z, ref->ddy.z};
    double scale = 1e-6;
    for (double v : d) scale = std::max(scale, std::abs(v));
    // Near edge-on, the derivatives have a pole within a fraction of a pixel: both float and double
    // estimates are unstable there, so those pixels are counted and bounded apart.
    const bool edgeOn = std::abs(glm::dot(glm::normalize(ref->position), ref->faceNormal)) < kEdgeOnCosine;
    e.edgeOnPixels += edgeOn;
    for (int k = 0; k < 4; ++k) worst(edgeOn ? e.derivativeEdgeOn : e.derivative, std::abs(a[12 + k] - d[k]) / scale);
  }
  return e;
}

}  // namespace visbuf::tools
