// The stress suite's independent reference: what the shading pass should have reconstructed at a pixel,
// computed in double precision by casting the pixel's ray at the triangle its IDs name (Moller-Trumbore on
// camera-relative world positions, so the barycentrics of the hit are the perspective-correct ones by
// construction, and derivatives come from rays a thousandth of a pixel apart). It shares no code with the
// GPU path's edge-function reconstruction (shaders/shared/barycentrics.h).
#pragma once

#include <cstdint>
#include <optional>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "visbuf/render/frame_math.h"
#include "visbuf/render/renderer.h"
#include "visbuf/scene/scene.h"

namespace visbuf::tools {

struct PixelReference {
  glm::dvec3 position{0.0};  // camera-relative world position of the hit
  double depth = 0.0;        // reverse-Z NDC depth
  glm::dvec3 normal{0.0};    // unit world normal (interpolated, inverse-transpose transformed)
  glm::dvec2 uv{0.0};
  glm::dvec3 lambda{0.0};
  glm::dvec3 ddx{0.0}, ddy{0.0};  // d(lambda) per pixel step in +x / +y
  glm::dvec3 faceNormal{0.0};     // unit normal of the triangle's plane
};

// The reference at pixel (x, y) for triangle `triangle` of LOD 0 of `object`. nullopt when the ray is
// parallel to the triangle's plane.
std::optional<PixelReference> referenceAtPixel(const Scene& scene, const Camera& camera, const FrameMath& math,
                                               uint32_t x, uint32_t y, uint32_t object, uint32_t triangle);

// Largest errors of the GPU's attribute records (FrameResult::attributes, LOD off) against the reference,
// over every covered pixel (or every `stride`-th one).
//
// Raw errors of a reconstruction from float inputs are ill-conditioned where a triangle is nearly edge-on or
// a sliver: a 1e-5-pixel shift of a triangle 1/1000 of a pixel wide moves its barycentrics by 1e-2. The
// bounded measures are therefore the well-conditioned ones: where on the screen the reconstructed point lies
// (position_px), how far off the triangle's plane (off_surface_rel), the barycentric error expressed as the
// screen displacement that explains it (lambda_px = |J^-1 dlambda|, J = d(lambda1, lambda2)/d(x, y)), and the derivatives relative to
// the pixel's largest, except on pixels of edge-on triangles, where they have a pole within the pixel. The raw errors (position, depth, normal, uv, lambda) are reported beside them.
inline constexpr double kEdgeOnCosine = 0.02;  // |cos(ray, triangle normal)| below this: edge-on (< 1.15 deg)

struct AttributeErrors {
  size_t pixels = 0;          // pixels compared
  double positionPixels = 0.0;  // screen distance (pixels) of the reconstructed point from the pixel centre
  double offSurface = 0.0;      // distance of the reconstructed point from the triangle's plane / |p_ref|
  double lambdaPixels = 0.0;    // |J^-1 (lambda - ref)|: the screen displacement (pixels) explaining it
  double position = 0.0;      // |p - p_ref| / |p_ref| (relative to the distance from the camera)
  double depth = 0.0;         // |d - d_ref| / d_ref
  double normal = 0.0;        // |n - n_ref| (unit vectors; ~ angle in radians)
  double uv = 0.0;            // largest |uv - uv_ref| component
  double lambda = 0.0;        // largest |lambda - lambda_ref| (lambda1, lambda2)
  double derivative = 0.0;    // largest |d - d_ref| / max(|d_ref| over the pixel's 4 derivatives, 1e-6)
  size_t edgeOnPixels = 0;    // pixels whose triangle is within kEdgeOnCosine of edge-on (ray . normal)
  double derivativeEdgeOn = 0.0;  // the derivative error over those pixels alone
  void merge(const AttributeErrors& o);
  nlohmann::ordered_json toJson() const;
};

AttributeErrors compareAttributes(const Scene& scene, const Camera& camera, const FrameResult& frame,
                                  size_t stride = 1);

}  // namespace visbuf::tools
