#include "visbuf/render/scene_motion.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

namespace visbuf {

namespace {
// A stable per-object hash in [0, 1): which objects move, and each path's phase.
double unitHash(uint64_t id, uint64_t seed, uint64_t salt) {
  Rng r(seed * 0x100000001B3ull ^ (id * 0x9E3779B97F4A7C15ull + salt));
  return r.uniform();
}
}  // namespace

SceneMotion::SceneMotion(const SceneMotionParams& params) : params_(params), rng_(params.seed) {}

Result<SceneMotion> SceneMotion::create(const Scene& scene, const SceneMotionParams& params) {
  if (!(params.moving >= 0.0 && params.moving <= 1.0))
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("scene motion: the moving fraction {} is outside [0, 1]", params.moving));
  if (!(params.churn >= 0.0 && params.churn <= 0.5))
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("scene motion: the churn fraction {} is outside [0, 0.5]", params.churn));
  if (scene.objects.empty()) return makeError(ErrorCode::InvalidArgument, "scene motion: the scene has no objects");
  SceneMotion m(params);
  std::vector<uint8_t> animated(scene.objects.size(), 0);
  for (const SkinnedObject& so : scene.skinnedObjects) animated[so.object] = 1;
  for (const RigidObject& ro : scene.rigidObjects) animated[ro.object] = 1;
  m.lo_ = glm::dvec3(1e300);
  m.hi_ = glm::dvec3(-1e300);
  for (const Object& o : scene.objects) {
    const glm::dvec3 p(o.transform[3]);
    m.lo_ = glm::min(m.lo_, p);
    m.hi_ = glm::max(m.hi_, p);
  }
  m.amplitude_ = std::max(0.03 * glm::length(m.hi_ - m.lo_), 1e-3);
  if (params.churn > 0.0) m.churnCount_ = std::max<uint32_t>(1, uint32_t(params.churn * double(scene.objects.size())));
  for (uint32_t id = 0; id < scene.objects.size(); ++id)
    if (!animated[id]) {
      m.templates_.push_back(scene.objects[id]);
      m.track(id, scene.objects[id], unitHash(id, params.seed, 1) < params.moving);
    }
  return m;
}

void SceneMotion::track(uint32_t id, const Object& o, bool mover) {
  if (id >= base_.size()) {
    base_.resize(id + 1, glm::dmat4(1.0));
    mover_.resize(id + 1, 0);
  }
  base_[id] = o.transform;
  mover_[id] = mover;
  removable_.push_back(id);
}

uint32_t SceneMotion::movingObjects() const {
  return uint32_t(std::count(mover_.begin(), mover_.end(), uint8_t(1)));
}

glm::dmat4 SceneMotion::pathTransform(uint32_t id, const glm::dmat4& base, uint32_t frame) const {
  // A closed Lissajous loop of 48 frames around the start, spinning about the object's own Y axis; the rotation
  // keeps the winding, so the object never changes draw list.
  const double phase = 6.283185307179586 * unitHash(id, params_.seed, 2);
  const double t = 6.283185307179586 * double(frame) / 48.0 + phase;
  const glm::dvec3 offset(std::sin(t) - std::sin(phase), 0.5 * (std::sin(2.0 * t) - std::sin(2.0 * phase)),
                          std::cos(t) - std::cos(phase));
  glm::dmat4 m = glm::rotate(base, t - phase, glm::dvec3(0.0, 1.0, 0.0));
  m[3] += glm::dvec4(amplitude_ * offset, 0.0);
  return m;
}

Result<SceneMotionFrame> SceneMotion::apply(Renderer& renderer, uint32_t frame) {
  SceneMotionFrame out;
  // Shown again: hidden three frames ago.
  for (size_t i = 0; i < hidden_.size();) {
    if (hidden_[i].first != frame) {
      ++i;
      continue;
    }
    const uint32_t id = hidden_[i].second;
    if (Status s = renderer.setVisible(id, true); !s) return s.error();
    removable_.push_back(id);
    hidden_[i] = hidden_.back();
    hidden_.pop_back();
    ++out.shown;
  }
  // Removed, then added (the new objects reuse the freed slots: their IDs keep the old visibility history).
  for (uint32_t k = 0; k < churnCount_ && !removable_.empty(); ++k) {
    const size_t pick = size_t(rng_.next() % removable_.size());
    const uint32_t id = removable_[pick];
    if (Status s = renderer.removeObject(id); !s) return s.error();
    removable_[pick] = removable_.back();
    removable_.pop_back();
    mover_[id] = 0;
    ++out.removed;
  }
  for (uint32_t k = 0; k < churnCount_ && !templates_.empty(); ++k) {
    Object o = templates_[size_t(rng_.next() % templates_.size())];
    o.transform[3] = glm::dvec4(rng_.uniform(lo_.x, hi_.x), rng_.uniform(lo_.y, hi_.y), rng_.uniform(lo_.z, hi_.z), 1.0);
    Result<uint32_t> id = renderer.addObject(o);
    if (!id) return id.error();
    track(*id, o, rng_.uniform() < params_.moving);
    ++out.added;
  }
  // Hidden for three frames.
  for (uint32_t k = 0; k < churnCount_ && !removable_.empty(); ++k) {
    const size_t pick = size_t(rng_.next() % removable_.size());
    const uint32_t id = removable_[pick];
    if (Status s = renderer.setVisible(id, false); !s) return s.error();
    removable_[pick] = removable_.back();
    removable_.pop_back();
    hidden_.push_back({frame + 3, id});
    ++out.hidden;
  }
  // Moved along their paths (hidden movers move too: they reappear elsewhere).
  std::vector<ObjectTransform> moves;
  for (uint32_t id = 0; id < mover_.size(); ++id)
    if (mover_[id]) moves.push_back({id, pathTransform(id, base_[id], frame + 1)});
  if (Status s = renderer.setTransforms(moves); !s) return s.error();
  out.moved = uint32_t(moves.size());
  return out;
}

}  // namespace visbuf
