// The scene's bounds over its whole animation (scene.h, animatedSceneBounds): what the default camera frames.
#include <algorithm>
#include <cmath>
#include <set>

#include "visbuf/scene/scene.h"

namespace visbuf {

namespace {

struct Box {
  glm::dvec3 lo{INFINITY}, hi{-INFINITY};
  void add(const glm::dvec3& c, double r) {
    lo = glm::min(lo, c - r);
    hi = glm::max(hi, c + r);
  }
  bool empty() const { return !(lo.x <= hi.x); }
};

// Sample times of clip `c`: every key time of its samplers (up to kMaxKeys) and a 30 Hz grid over [0, duration]
// (at most kMaxGrid + 1 points), both ends included; `budget` caps the total (evenly thinned, ends kept).
std::vector<double> sampleTimes(const AnimationClip& clip, size_t budget) {
  constexpr size_t kMaxKeys = 4096, kMaxGrid = 240;
  std::set<double> times{0.0, clip.duration};
  for (const AnimationSampler& s : clip.samplers)
    for (float t : s.times)
      if (times.size() < kMaxKeys && t >= 0.0f && double(t) <= clip.duration) times.insert(double(t));
  const size_t grid = size_t(std::clamp(std::ceil(clip.duration * 30.0), 1.0, double(kMaxGrid)));
  for (size_t k = 0; k <= grid; ++k) times.insert(clip.duration * double(k) / double(grid));
  std::vector<double> all(times.begin(), times.end());
  budget = std::max<size_t>(budget, 2);
  if (all.size() <= budget) return all;
  std::vector<double> thinned;
  for (size_t k = 0; k < budget; ++k) thinned.push_back(all[k * (all.size() - 1) / (budget - 1)]);
  return thinned;
}

// The clips an animated object is framed over: every clip of the scene (a host may play any of them), and the rest
// pose (-1).
std::vector<int32_t> framedClips(const Scene& scene) {
  std::vector<int32_t> clips{-1};
  for (size_t c = 0; c < scene.animations.size(); ++c) clips.push_back(int32_t(c));
  return clips;
}

}  // namespace

glm::dvec4 animatedSceneBounds(const Scene& scene) {
  if (scene.objects.empty()) return glm::dvec4(0.0);
  std::vector<uint8_t> animated(scene.objects.size(), 0);
  for (const SkinnedObject& so : scene.skinnedObjects) animated[so.object] = 1;
  for (const RigidObject& ro : scene.rigidObjects) animated[ro.object] = 1;
  std::vector<glm::dvec4> spheres;  // world spheres whose union the bound contains
  for (size_t i = 0; i < scene.objects.size(); ++i)
    if (!animated[i]) spheres.push_back(objectBoundsWorld(scene, scene.objects[i]));
  const std::vector<int32_t> clips = framedClips(scene);
  auto timesOf = [&](int32_t clip, size_t budget) {
    return clip < 0 ? std::vector<double>{0.0} : sampleTimes(scene.animations[size_t(clip)], budget);
  };
  // Rigid objects: one pose of the hierarchy per clip and time, shared by all (rigidObjectTransform's matrix,
  // placement * global(node); the phase is irrelevant: the samples cover the whole looping clip), boxed per object.
  std::vector<Box> rigidBoxes(scene.rigidObjects.size());
  if (!scene.rigidObjects.empty())
    for (int32_t clip : clips)
      for (double t : timesOf(clip, SIZE_MAX)) {
        Pose pose = restPose(scene.nodes);
        if (clip >= 0) sampleClip(scene.animations[size_t(clip)], t, true, pose);
        const std::vector<glm::dmat4> global = globalMatrices(scene.nodes, pose);
        for (size_t i = 0; i < scene.rigidObjects.size(); ++i) {
          const RigidObject& ro = scene.rigidObjects[i];
          const Mesh& mesh = scene.meshes[scene.objects[ro.object].mesh];
          const glm::dmat4 m = ro.placement * global[size_t(ro.node)];
          const glm::dvec3 c(m * glm::dvec4(glm::dvec3(mesh.boundsSphere), 1.0));
          const double r = double(mesh.boundsSphere.w) * maxScaleOf(m);
          if (std::isfinite(r) && std::isfinite(c.x + c.y + c.z)) rigidBoxes[i].add(c, r);
        }
      }
  for (const Box& b : rigidBoxes)
    if (!b.empty()) spheres.push_back({(b.lo + b.hi) * 0.5, glm::length(b.hi - b.lo) * 0.5});
  // Skinned (and morphed) objects: their vertices, skinned on the CPU at each sample time (the exact pose), boxed per
  // sample. About 2^25 vertex evaluations in all (a second or two): the sample count per clip shrinks with the
  // scene's skinned vertices, to no fewer than the clip's two ends.
  size_t skinnedVertices = 1;
  for (const SkinnedObject& so : scene.skinnedObjects)
    skinnedVertices += scene.meshes[scene.objects[so.object].mesh].vertices.size();
  const size_t budget = std::max<size_t>(2, (size_t{1} << 25) / skinnedVertices / clips.size());
  for (const SkinnedObject& so : scene.skinnedObjects) {
    const Mesh& mesh = scene.meshes[scene.objects[so.object].mesh];
    Box box;
    for (int32_t clip : clips) {
      SkinnedObject posed = so;
      posed.clip = clip;
      posed.timeOffset = 0.0;
      for (double t : timesOf(clip, budget)) {
        const std::vector<glm::dmat4> joints = skinnedObjectJoints(scene, posed, t);
        const std::vector<double> weights = skinnedObjectMorphWeights(scene, posed, t);
        for (uint32_t v = 0; v < mesh.vertices.size(); ++v) {
          const glm::dvec3 p = skinPosition(morphVertex(mesh, v, weights).position, mesh.skinVertices[v], joints);
          const glm::dvec3 w(so.placement * glm::dvec4(p, 1.0));
          if (std::isfinite(w.x + w.y + w.z)) box.add(w, 0.0);
        }
      }
    }
    if (!box.empty()) spheres.push_back({(box.lo + box.hi) * 0.5, glm::length(box.hi - box.lo) * 0.5});
  }
  Box all;
  for (const glm::dvec4& s : spheres) all.add(glm::dvec3(s), s.w);
  if (all.empty()) return glm::dvec4(0.0);
  const glm::dvec3 centre = (all.lo + all.hi) * 0.5;
  double radius = 0.0;
  for (const glm::dvec4& s : spheres) radius = std::max(radius, glm::length(glm::dvec3(s) - centre) + s.w);
  return {centre, radius};
}

}  // namespace visbuf
