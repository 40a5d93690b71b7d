// Deterministic scene changes for tests, benchmarks and `visbuf render --moving`: every frame, a fixed fraction
// of the scene's movable objects travel along closed paths, and a few objects are removed, added and hidden, all
// through the Renderer's public scene-update API (setTransforms, addObject, removeObject, setVisible).
//
// Two SceneMotion objects made with the same scene and parameters, applied to two renderers created from that
// scene with the same RendererConfig::spareObjects, make identical changes frame by frame (same object IDs):
// the tests compare a renderer that culls with one that does not.
#pragma once

#include <cstdint>
#include <vector>

#include "visbuf/core/result.h"
#include "visbuf/render/renderer.h"
#include "visbuf/scene/generate.h"

namespace visbuf {

struct SceneMotionParams {
  double moving = 0.1;  // fraction of the movable objects that move every frame, [0, 1]
  // Objects removed, added and hidden every frame, as a fraction of the scene's objects (at least one each when
  // non-zero); an object hidden at frame f is shown again at frame f + 3.
  double churn = 0.0;
  uint64_t seed = 1;
};

// What apply() changed in one frame.
struct SceneMotionFrame {
  uint32_t moved = 0, added = 0, removed = 0, hidden = 0, shown = 0;
};

class SceneMotion {
 public:
  // Movable: scene objects that are neither skinned nor node-animated (their poses place those). Fails for a
  // fraction outside [0, 1] or a scene whose objects cannot be bounded (no objects).
  static Result<SceneMotion> create(const Scene& scene, const SceneMotionParams& params);
  // RendererConfig::spareObjects that the churn needs (the first frame adds before any slot is freed twice).
  uint32_t spareObjects() const { return churnCount_; }
  // Applies frame `frame`'s changes (frames must be applied in order 0, 1, 2, ...). A refusal by the renderer is
  // returned as it is (the renderer then holds part of that frame's changes).
  Result<SceneMotionFrame> apply(Renderer& renderer, uint32_t frame);
  // The transform that apply() gives moving object `id` at frame `frame` (its path), from its transform `base`.
  glm::dmat4 pathTransform(uint32_t id, const glm::dmat4& base, uint32_t frame) const;
  uint32_t movingObjects() const;

 private:
  explicit SceneMotion(const SceneMotionParams& params);
  void track(uint32_t id, const Object& o, bool mover);

  SceneMotionParams params_;
  Rng rng_;
  double amplitude_ = 1.0;                 // path radius (world units): 3 % of the scene's extent
  glm::dvec3 lo_{0.0}, hi_{0.0};           // where added objects appear (the scene objects' origins' box)
  uint32_t churnCount_ = 0;
  std::vector<Object> templates_;          // what added objects copy (the movable scene objects)
  std::vector<glm::dmat4> base_;           // per object ID: its transform when it started moving
  std::vector<uint8_t> mover_;             // per object ID: moves every frame
  std::vector<uint32_t> removable_;        // live IDs apply() may remove or hide (movable objects only)
  std::vector<std::pair<uint32_t, uint32_t>> hidden_;  // (frame to show again, ID)
};

}  // namespace visbuf
