// A per-pixel judge of the two shading paths: for every pixel where the visbuf path or the forward path shows a
// triangle, the exact colour computed in double precision on the CPU (the pixel centre's ray against the
// triangle, barycentrics of the hit, attributes interpolated from the scene's CPU mesh data, the material, and
// shadeReference of brdf_reference.h), and each path's distance from it. Where the paths differ, it says which
// one is closer and by how much. Independent of the GPU code: it shares no arithmetic with the shaders.
//
// What it judges: opaque and masked materials with their textures (texture_reference.h: the shader's filtering and
// mip selection, from the exact uv derivatives), normal maps and vertex colours, the material extensions (unlit,
// clearcoat with its textures and normal, emissive strength); static and node-animated objects;
// single-sampled frames. Block-compressed texels are the spec's unrounded palette; devices decode BC at their own
// precision (lavapipe nearer 8 bits), which both paths share: on BC-textured smooth surfaces both are off by the
// same texel error, and the verdict of which is closer still holds. Pixels it cannot judge are counted by reason,
// never guessed: skinned or morphed objects (their vertices come from the skinning pass), rays parallel to the
// triangle. Scenes with BLEND materials are
// refused: the transparency pass draws over the IDs, so the IDs do not say what a pixel shows.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/core/result.h"
#include "visbuf/render/frame_math.h"
#include "visbuf/render/renderer.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

// A view ray in camera-relative world space (the camera at the origin): origin + t dir.
struct PixelRay {
  glm::dvec3 origin{0.0};  // perspective: the camera (0); orthographic: the pixel's point on the plane z_view = 0
  glm::dvec3 dir{0.0, 0.0, -1.0};  // not normalised (orthographic: the unit view direction)
  glm::dvec3 at(double t) const { return origin + t * dir; }
};

// The ray through pixel position (px, py) (pixel units from the top-left corner; the centre of pixel (x, y) is
// (x + 0.5, y + 0.5)).
PixelRay pixelRay(const FrameMath& math, double px, double py);

// Moller-Trumbore along `ray` against triangle v (camera-relative), without the inside test (derivative rays may
// leave the triangle): (t, barycentrics). nullopt when the ray is parallel to its plane.
std::optional<std::pair<double, glm::dvec3>> intersectTriangle(const glm::dvec3 v[3], const PixelRay& ray);

// One path's colour against the exact colour, over the pixels judged (RGB, unclamped: rgba16f keeps values above
// 1, and so does the reference).
struct PathAccuracy {
  double maxAbs = 0.0;      // largest channel |path - exact|
  double meanAbs = 0.0;     // mean over judged pixels and RGB channels
  double psnr = INFINITY;   // dB, peak 1.0, over judged pixels and RGB channels
  size_t over8Bit = 0;      // judged pixels whose largest channel error exceeds 1/255
  // Largest channel error beyond rgba16f rounding: |path - exact| less the half-float spacing at the exact value
  // (Vulkan allows rounding to nearest or towards zero; 0: every channel is what converting the exact colour could
  // give). The output format's share of maxAbs grows with the value (up to 9.8e-4 in [1, 2)); this is the
  // shading's own.
  double maxBeyondRounding = 0.0;
};

struct JudgeOptions {
  double animationTime = 0.0;  // the frames' FrameOptions::animationTime (places node-animated objects)
  // Per-pixel error: the largest RGB channel difference. Pixels whose two errors differ by at most this are a
  // tie. 0: only equal errors tie (both paths round to rgba16f, so identical colours are common).
  double tieTolerance = 0.0;
};

struct PixelJudgement {
  uint32_t width = 0, height = 0;
  size_t covered = 0;            // pixels where either path shows a triangle
  size_t judged = 0;             // of those: an exact colour was computed and both paths compared with it
  size_t notJudgedSkinned = 0;   // the claimed object is skinned or morphed
  size_t notJudgedParallel = 0;  // the pixel's ray is parallel to the claimed triangle
  size_t coverageMismatch = 0;   // covered pixels where the paths show different triangles (judged: the exact
                                 // colour is that of the claimed triangle the ray hits first, or the background)
  PathAccuracy visbuf, forward;
  // Judged pixels whose two colours differ, split by which path is closer to the exact colour.
  size_t differing = 0;
  size_t visbufCloser = 0, forwardCloser = 0, ties = 0;
  double visbufMargin = 0.0, forwardMargin = 0.0;        // mean error difference where each is closer
  double visbufMaxMargin = 0.0, forwardMaxMargin = 0.0;  // largest error difference where each is closer
  // RGBA per pixel, linear: red = log10 of the visbuf path's error, green = the forward path's, each mapped from
  // [1e-5, 1e-1] to [0, 1] (yellow: both off, red: visbuf off, green: forward off); blue 0.5 where not judged;
  // black where neither path shows a triangle.
  std::vector<float> heatMap;
};

// Judges two frames of the same scene, camera and size: `visbuf` (RenderPath::Visbuf) and `forward`
// (RenderPath::Forward), each rendered with readIds and readColor. The LOD each object was drawn at comes from the
// frame's drawnObjects / drawnLods when it was rendered with readDraws, else LOD 0 (render with lodErrorPixels 0).
// Errors (InvalidArgument): frames of different sizes, without IDs or colour, multisampled IDs, or that drew LODs
// above 0 (FrameStats::cull.lodHistogram) without drawnLods; a scene with BLEND materials (see the top); an ID
// naming an object or triangle the scene does not have.
Result<PixelJudgement> judgePixels(const Scene& scene, const Camera& camera, const FrameResult& visbuf,
                                   const FrameResult& forward, const JudgeOptions& options = {});

// Judges a multisampled frame: `visbuf` rendered with `samples` (2 or 4) per pixel, readIds (one ID per sample)
// and readColor; `forward` the forward path's resolved colour (readColor) of the same scene, camera, size and
// samples. The exact colour of a pixel is what a resolve of exact samples gives: the mean over its standard sample
// locations of the exact colour, at that location, of the triangle the visbuf sample shows (the background where it
// shows nothing). Both resolved colours are measured against it; coverageMismatch counts the pixels whose samples
// show different triangles (the edges). The checks and errors of judgePixels, for the visbuf frame's IDs.
Result<PixelJudgement> judgeMsaaPixels(const Scene& scene, const Camera& camera, const FrameResult& visbuf,
                                       const FrameResult& forward, uint32_t samples, const JudgeOptions& options = {});

}  // namespace visbuf
