// Skeletal animation on the CPU (animation.h): validation, keyframe sampling (glTF 2.0 appendix C),
// hierarchy evaluation in double precision, reference skinning and conservative skinned bounds.
#include "visbuf/scene/animation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "visbuf/scene/scene.h"  // maxScaleOf

namespace visbuf {

namespace {

Error malformed(std::string message) { return makeError(ErrorCode::MalformedInput, std::move(message)); }

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}
bool finite(glm::dvec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool affine(const glm::dmat4& m) {
  return m[0][3] == 0.0 && m[1][3] == 0.0 && m[2][3] == 0.0 && m[3][3] == 1.0;
}

// Visits the nodes parents-first: calls fn(node) once per node after fn(parent). Returns false (having
// visited only part of the nodes) when a parent index is out of range or the parents form a cycle.
template <typename Fn>
bool forEachParentFirst(const std::vector<SceneNode>& nodes, Fn&& fn) {
  enum : uint8_t { kNew, kOnPath, kDone };
  std::vector<uint8_t> state(nodes.size(), kNew);
  std::vector<size_t> path;
  for (size_t start = 0; start < nodes.size(); ++start) {
    // Climb from `start` to the first node already done (or a root), then visit the climbed path downwards.
    for (size_t i = start; state[i] == kNew;) {
      state[i] = kOnPath;
      path.push_back(i);
      const int32_t parent = nodes[i].parent;
      if (parent < 0) break;
      if (static_cast<size_t>(parent) >= nodes.size() || state[static_cast<size_t>(parent)] == kOnPath)
        return false;
      i = static_cast<size_t>(parent);
    }
    for (auto it = path.rbegin(); it != path.rend(); ++it) {
      fn(*it);
      state[*it] = kDone;
    }
    path.clear();
  }
  return true;
}

// The glTF spherical interpolation (appendix C): normalised keys, shortest arc, nlerp when nearly parallel.
glm::dquat slerpShortest(glm::dquat a, glm::dquat b, double u) {
  a = glm::normalize(a);
  b = glm::normalize(b);
  double d = glm::dot(a, b);
  if (d < 0.0) {
    b = -b;
    d = -d;
  }
  if (d > 1.0 - 1e-9) return glm::normalize(a * (1.0 - u) + b * u);
  const double theta0 = std::acos(d);
  const double theta = theta0 * u;
  const double s1 = std::sin(theta) / std::sin(theta0);
  const double s0 = std::cos(theta) - d * s1;
  return glm::normalize(a * s0 + b * s1);
}

glm::dquat quatAt(const float* v) { return glm::dquat(v[3], v[0], v[1], v[2]); }  // glTF order x, y, z, w

void normaliseQuat(std::span<double> q) {
  const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(len > 0.0)) {
    q[0] = q[1] = q[2] = 0.0;
    q[3] = 1.0;
    return;
  }
  for (int c = 0; c < 4; ++c) q[c] /= len;
}

}  // namespace

glm::dmat4 NodeTransform::matrix() const {
  const double x = rotation.x, y = rotation.y, z = rotation.z, w = rotation.w;
  glm::dmat3 rs(1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),   // column 0
                2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),   // column 1
                2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y));  // column 2
  for (int c = 0; c < 3; ++c) rs[c] *= scale[c];
  glm::dmat4 m(rs);
  m[3] = glm::dvec4(translation, 1.0);
  return m;
}

// --- validation --------------------------------------------------------------------------------------------

Status validateNodes(const std::vector<SceneNode>& nodes) {
  for (size_t i = 0; i < nodes.size(); ++i) {
    const SceneNode& n = nodes[i];
    const std::string where = fmt::format("node {} '{}'", i, n.name);
    if (n.parent < -1 || (n.parent >= 0 && static_cast<size_t>(n.parent) >= nodes.size()))
      return malformed(fmt::format("{}: parent {} does not exist ({} nodes)", where, n.parent, nodes.size()));
    const glm::dquat& q = n.rest.rotation;
    if (!finite(n.matrix) || !finite(n.rest.translation) || !finite(n.rest.scale) ||
        !std::isfinite(glm::dot(q, q)))
      return malformed(where + ": non-finite transform");
    if (std::abs(glm::length(q) - 1.0) > 1e-3)
      return malformed(where + ": rotation is not a unit quaternion");
  }
  if (!forEachParentFirst(nodes, [](size_t) {})) return malformed("node hierarchy has a cycle");
  return {};
}

Status validateSkin(const Skin& skin, size_t nodeCount, const std::string& where) {
  if (skin.joints.empty()) return malformed(where + ": no joints");
  if (skin.joints.size() > 65536)
    return malformed(fmt::format("{}: {} joints (at most 65536)", where, skin.joints.size()));
  if (skin.inverseBindMatrices.size() != skin.joints.size())
    return malformed(fmt::format("{}: {} inverse bind matrices for {} joints", where,
                                 skin.inverseBindMatrices.size(), skin.joints.size()));
  for (size_t j = 0; j < skin.joints.size(); ++j) {
    if (skin.joints[j] >= nodeCount)
      return malformed(fmt::format("{}: joint {} is node {}, which does not exist ({} nodes)", where, j,
                                   skin.joints[j], nodeCount));
    if (!finite(skin.inverseBindMatrices[j]))
      return malformed(fmt::format("{}: inverse bind matrix {} is not finite", where, j));
    if (!affine(skin.inverseBindMatrices[j]))
      return malformed(
          fmt::format("{}: inverse bind matrix {} is not affine (last row must be 0 0 0 1)", where, j));
  }
  if (skin.skeleton < -1 || (skin.skeleton >= 0 && static_cast<size_t>(skin.skeleton) >= nodeCount))
    return malformed(fmt::format("{}: skeleton node {} does not exist", where, skin.skeleton));
  return {};
}

namespace {

Status validateSampler(const AnimationSampler& s, const std::string& where) {
  if (s.times.empty()) return malformed(where + ": no keyframes");
  if (s.components == 0 || s.interpolation > Interpolation::CubicSpline)
    return malformed(fmt::format("{}: invalid interpolation {} or {} components", where,
                                 static_cast<uint32_t>(s.interpolation), s.components));
  for (size_t k = 0; k < s.times.size(); ++k) {
    if (!std::isfinite(s.times[k])) return malformed(fmt::format("{}: key time {} is not finite", where, k));
    if (k > 0 && !(s.times[k] > s.times[k - 1]))
      return malformed(fmt::format("{}: key times are not strictly increasing (key {}: {} after {})", where,
                                   k, s.times[k], s.times[k - 1]));
  }
  const uint64_t perKey = uint64_t{s.components} * (s.interpolation == Interpolation::CubicSpline ? 3 : 1);
  if (s.values.size() != s.times.size() * perKey)
    return malformed(fmt::format("{}: {} output values for {} keys (expected {} per key)", where,
                                 s.values.size(), s.times.size(), perKey));
  for (size_t i = 0; i < s.values.size(); ++i)
    if (!std::isfinite(s.values[i]))
      return malformed(fmt::format("{}: output value {} is not finite", where, i));
  return {};
}

// Translation and scale are vec3, rotation a quaternion, weights any number of morph targets.
bool pathFits(AnimationPath path, uint32_t components) {
  switch (path) {
    case AnimationPath::Translation:
    case AnimationPath::Scale: return components == 3;
    case AnimationPath::Rotation: return components == 4;
    case AnimationPath::Weights: return components > 0;
  }
  return false;  // an unknown path value (from a damaged pack)
}

}  // namespace

Status validateClip(const AnimationClip& clip, const std::vector<SceneNode>& nodes,
                    const std::string& where) {
  double duration = 0.0;
  for (size_t i = 0; i < clip.samplers.size(); ++i) {
    if (Status s = validateSampler(clip.samplers[i], fmt::format("{} sampler {}", where, i)); !s) return s;
    duration = std::max(duration, double(clip.samplers[i].times.back()));
  }
  if (clip.duration != duration)
    return malformed(
        fmt::format("{}: duration {} differs from the last key time {}", where, clip.duration, duration));
  for (size_t i = 0; i < clip.channels.size(); ++i) {
    const AnimationChannel& c = clip.channels[i];
    const std::string cw = fmt::format("{} channel {}", where, i);
    if (c.sampler >= clip.samplers.size())
      return malformed(
          fmt::format("{}: sampler {} does not exist ({} samplers)", cw, c.sampler, clip.samplers.size()));
    if (c.node >= nodes.size())
      return malformed(fmt::format("{}: target node {} does not exist ({} nodes)", cw, c.node, nodes.size()));
    if (nodes[c.node].hasMatrix)
      return malformed(
          fmt::format("{}: target node {} has a matrix (glTF: animated nodes use TRS)", cw, c.node));
    const uint32_t components = clip.samplers[c.sampler].components;
    if (!pathFits(c.path, components))
      return malformed(fmt::format("{}: path {} does not fit {} components", cw,
                                   static_cast<uint32_t>(c.path), components));
  }
  return {};
}

// --- sampling ----------------------------------------------------------------------------------------------

double clipTime(const AnimationClip& clip, double time, bool loop) {
  if (!loop) return time;
  if (!(clip.duration > 0.0) || !std::isfinite(time)) return 0.0;
  const double t = std::fmod(time, clip.duration);
  return t < 0.0 ? t + clip.duration : t;
}

void sampleSampler(const AnimationSampler& s, AnimationPath path, double time, std::span<double> out) {
  const size_t n = s.components;
  const bool cubic = s.interpolation == Interpolation::CubicSpline;
  const size_t stride = cubic ? 3 * n : n;
  auto value = [&](size_t key) { return s.values.data() + key * stride + (cubic ? n : 0); };
  auto copyKey = [&](size_t key) {
    for (size_t c = 0; c < n; ++c) out[c] = value(key)[c];
  };
  const size_t keys = s.times.size();
  // k: the last key with times[k] <= time (clamped to the first / last key outside the range).
  if (keys == 1 || !(time > s.times.front())) {
    copyKey(0);
  } else if (time >= s.times.back()) {
    copyKey(keys - 1);
  } else {
    const size_t k = size_t(std::upper_bound(s.times.begin(), s.times.end(), time) - s.times.begin()) - 1;
    const double t0 = s.times[k], t1 = s.times[k + 1], dt = t1 - t0, u = (time - t0) / dt;
    if (s.interpolation == Interpolation::Step) {
      copyKey(k);
    } else if (!cubic && path == AnimationPath::Rotation) {
      const glm::dquat q = slerpShortest(quatAt(value(k)), quatAt(value(k + 1)), u);
      out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
    } else if (!cubic) {
      for (size_t c = 0; c < n; ++c) out[c] = value(k)[c] * (1.0 - u) + double(value(k + 1)[c]) * u;
    } else {
      // Hermite basis (glTF appendix C): p = h00 v_k + h10 dt b_k + h01 v_k+1 + h11 dt a_k+1, where b_k is
      // key k's out-tangent and a_k+1 key k+1's in-tangent.
      const double u2 = u * u, u3 = u2 * u;
      const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
      const float* outTangent = value(k) + n;
      const float* inTangent = value(k + 1) - n;
      for (size_t c = 0; c < n; ++c)
        out[c] =
            h00 * value(k)[c] + h10 * dt * outTangent[c] + h01 * value(k + 1)[c] + h11 * dt * inTangent[c];
    }
  }
  if (path == AnimationPath::Rotation && n == 4) normaliseQuat(out);
}

Pose restPose(const std::vector<SceneNode>& nodes) {
  Pose pose;
  pose.locals.reserve(nodes.size());
  for (const SceneNode& n : nodes) pose.locals.push_back(n.rest);
  pose.weights.resize(nodes.size());
  return pose;
}

void sampleClip(const AnimationClip& clip, double time, bool loop, Pose& pose) {
  const double t = clipTime(clip, time, loop);
  std::vector<double> buffer;
  pose.weights.resize(pose.locals.size());
  for (const AnimationChannel& c : clip.channels) {
    if (c.node >= pose.locals.size() || c.sampler >= clip.samplers.size()) continue;
    const AnimationSampler& s = clip.samplers[c.sampler];
    buffer.assign(s.components, 0.0);
    sampleSampler(s, c.path, t, buffer);
    NodeTransform& local = pose.locals[c.node];
    switch (c.path) {
      case AnimationPath::Translation: local.translation = {buffer[0], buffer[1], buffer[2]}; break;
      case AnimationPath::Rotation:
        local.rotation = glm::dquat(buffer[3], buffer[0], buffer[1], buffer[2]);
        break;
      case AnimationPath::Scale: local.scale = {buffer[0], buffer[1], buffer[2]}; break;
      case AnimationPath::Weights: pose.weights[c.node] = buffer; break;
    }
  }
}

std::vector<glm::dmat4> globalMatrices(const std::vector<SceneNode>& nodes, const Pose& pose) {
  std::vector<glm::dmat4> globals(nodes.size(), glm::dmat4(1.0));
  forEachParentFirst(nodes, [&](size_t i) {
    const SceneNode& n = nodes[i];
    const glm::dmat4 local = n.hasMatrix ? n.matrix : pose.locals[i].matrix();
    globals[i] = n.parent >= 0 ? globals[static_cast<size_t>(n.parent)] * local : local;
  });
  return globals;
}

std::vector<glm::dmat4> jointMatrices(const Skin& skin, const std::vector<glm::dmat4>& globals) {
  std::vector<glm::dmat4> out(skin.joints.size());
  for (size_t j = 0; j < skin.joints.size(); ++j)
    out[j] = globals[skin.joints[j]] * skin.inverseBindMatrices[j];
  return out;
}

std::vector<glm::mat4> jointMatricesRelative(const Skin& skin, const std::vector<glm::dmat4>& globals,
                                             glm::dvec3 origin) {
  std::vector<glm::mat4> out(skin.joints.size());
  for (size_t j = 0; j < skin.joints.size(); ++j) {
    glm::dmat4 m = globals[skin.joints[j]] * skin.inverseBindMatrices[j];
    for (int c = 0; c < 4; ++c) m[c] -= glm::dvec4(origin * m[c].w, 0.0);  // T(-origin) * m
    out[j] = glm::mat4(m);
  }
  return out;
}

// --- reference skinning ------------------------------------------------------------------------------------

glm::dmat4 blendedJointMatrix(const SkinVertex& skin, std::span<const glm::dmat4> joints) {
  glm::dmat4 b(0.0);
  for (int i = 0; i < kSkinInfluences; ++i) {
    if (skin.weights[i] == 0.0f) continue;
    b += joints[skin.joints[i]] * double(skin.weights[i]);
  }
  return b;
}

glm::dvec3 skinPosition(glm::dvec3 position, const SkinVertex& skin, std::span<const glm::dmat4> joints) {
  return glm::dvec3(blendedJointMatrix(skin, joints) * glm::dvec4(position, 1.0));
}

glm::dvec3 skinNormal(glm::dvec3 normal, const SkinVertex& skin, std::span<const glm::dmat4> joints) {
  const glm::dmat3 b(blendedJointMatrix(skin, joints));
  // Cofactor matrix = det * inverse-transpose; its columns are cross products of b's columns.
  const glm::dmat3 cofactor(glm::cross(b[1], b[2]), glm::cross(b[2], b[0]), glm::cross(b[0], b[1]));
  const glm::dvec3 n = cofactor * normal * (glm::determinant(b) < 0.0 ? -1.0 : 1.0);
  const double len = glm::length(n);
  return len > 0.0 ? n / len : glm::dvec3(0.0);
}

glm::dvec3 skinTangent(glm::dvec3 tangent, const SkinVertex& skin, std::span<const glm::dmat4> joints) {
  const glm::dvec3 t = glm::dmat3(blendedJointMatrix(skin, joints)) * tangent;
  const double len = glm::length(t);
  return len > 0.0 ? t / len : glm::dvec3(0.0);
}

// --- bounds ------------------------------------------------------------------------------------------------

std::vector<glm::dvec4> jointInfluenceSpheres(std::span<const glm::vec3> positions,
                                              std::span<const SkinVertex> skin, size_t jointCount) {
  // Centre: the box centre of the influenced vertices; radius: the farthest of them from it.
  std::vector<glm::dvec3> lo(jointCount, glm::dvec3(INFINITY)), hi(jointCount, glm::dvec3(-INFINITY));
  auto forInfluences = [&](auto&& fn) {
    for (size_t v = 0; v < positions.size() && v < skin.size(); ++v)
      for (int i = 0; i < kSkinInfluences; ++i)
        if (skin[v].weights[i] > 0.0f && skin[v].joints[i] < jointCount)
          fn(skin[v].joints[i], glm::dvec3(positions[v]));
  };
  forInfluences([&](size_t j, glm::dvec3 p) {
    lo[j] = glm::min(lo[j], p);
    hi[j] = glm::max(hi[j], p);
  });
  std::vector<glm::dvec4> spheres(jointCount, glm::dvec4(0.0, 0.0, 0.0, -1.0));
  for (size_t j = 0; j < jointCount; ++j)
    if (lo[j].x <= hi[j].x) spheres[j] = glm::dvec4((lo[j] + hi[j]) * 0.5, 0.0);
  forInfluences([&](size_t j, glm::dvec3 p) {
    spheres[j].w = std::max(spheres[j].w, glm::length(p - glm::dvec3(spheres[j])));
  });
  return spheres;
}

// Proof that the result contains every skinned vertex p' = sum_i w_i J_i p (w_i >= 0, sum w_i = 1):
//   1. For each influence i of p (w_i > 0), p lies in joint i's bind-space sphere (c_i, r_i) by construction,
//      so J_i p lies in the posed sphere S_i = (J_i c_i, s_i r_i) for any s_i >= the spectral norm of J_i's
//      3x3 part (an affine map moves two points at most s_i times their distance apart); maxScaleOf() is
//      such a bound (Gershgorin on A^T A, never below the true norm).
//   2. p' is a convex combination of the points J_i p, each in some S_i, so p' lies in the convex hull of
//      the union of the S_i.
//   3. The returned sphere contains every S_i (its radius is max |centre - J_i c_i| + s_i r_i) and is
//      convex, so it contains that hull, hence p'.
// Rounding: SkinVertex weights are floats summing to 1 within a few ulp (|sum - 1| <= 1e-6), which moves p'
// by at most 1e-6 |p'|; GPU float skinning adds a similar relative error. The radius is padded by
// 1e-5 (|centre| + radius), which covers both with a wide margin.
glm::dvec4 skinnedBoundsSphere(std::span<const glm::dvec4> spheres, std::span<const glm::dmat4> joints) {
  if (joints.size() < spheres.size()) return glm::dvec4(0.0, 0.0, 0.0, INFINITY);
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  std::vector<glm::dvec4> posed;
  for (size_t j = 0; j < spheres.size(); ++j) {
    if (spheres[j].w < 0.0) continue;
    if (!affine(joints[j])) return glm::dvec4(0.0, 0.0, 0.0, INFINITY);
    const glm::dvec3 c(joints[j] * glm::dvec4(glm::dvec3(spheres[j]), 1.0));
    const double r = spheres[j].w * maxScaleOf(joints[j]);
    posed.emplace_back(c, r);
    lo = glm::min(lo, c - r);
    hi = glm::max(hi, c + r);
  }
  if (posed.empty()) return glm::dvec4(0.0, 0.0, 0.0, -1.0);
  const glm::dvec3 centre = (lo + hi) * 0.5;
  double radius = 0.0;
  for (const glm::dvec4& s : posed) radius = std::max(radius, glm::length(glm::dvec3(s) - centre) + s.w);
  radius += 1e-5 * (glm::length(centre) + radius);
  return glm::dvec4(centre, radius);
}

}  // namespace visbuf
