#include "visbuf/render/animation_state.h"

#include <algorithm>
#include <chrono>
#include <thread>

#include <fmt/format.h>

#include "visbuf/scene/animation.h"

namespace visbuf {

Result<std::unique_ptr<AnimationState>> AnimationState::create(gpu::Device& device, const Scene& scene,
                                                               const GpuScene& gpuScene, bool gpuBounds) {
  if (gpuScene.skinned.empty()) return std::unique_ptr<AnimationState>();
  std::unique_ptr<AnimationState> a(new AnimationState(scene, gpuScene));
  a->regions_ = gpuScene.skinned;
  a->rest_ = restPose(scene.nodes);
  a->regionOfObject_.assign(scene.objects.size(), -1);
  uint32_t joints = 0;
  for (size_t i = 0; i < a->regions_.size(); ++i) {
    const GpuScene::SkinnedRegion& r = a->regions_[i];
    const SkinnedObject& so = scene.skinnedObjects[i];
    const Skin& skin = scene.skins[so.skin];
    a->regionOfObject_[r.object] = int32_t(i);
    a->firstJoint_.push_back(joints);
    joints += uint32_t(skin.joints.size());
    a->maxVertices_ = std::max(a->maxVertices_, r.vertexCount);
    a->vertexCount_ += r.vertexCount;
    auto key = std::make_pair(r.sourceMesh, so.skin);
    if (!a->spheres_.count(key)) {
      const Mesh& mesh = scene.meshes[r.sourceMesh];
      std::vector<glm::vec3> positions;
      positions.reserve(mesh.vertices.size());
      for (uint32_t v = 0; v < mesh.vertices.size(); ++v) positions.push_back(mesh.position(v));
      a->spheres_[key] = jointInfluenceSpheres(positions, mesh.skinVertices, skin.joints.size());
    }
  }
  // Morph weights: one row of 4 per 4 targets of each morphing instance, after every instance's joint rows.
  uint64_t weightRows = 0;
  a->morphWeightRow_.assign(a->regions_.size(), 0);
  for (size_t i = 0; i < a->regions_.size(); ++i) {
    const GpuScene::SkinnedRegion& r = a->regions_[i];
    if (r.morphTargets == 0) continue;
    a->morphWeightRow_[i] = uint32_t(3 * uint64_t(joints) + weightRows);
    weightRows += (r.morphTargets + 3) / 4;
    if (a->morphMaxDelta_.count(r.sourceMesh)) continue;
    const Mesh& mesh = scene.meshes[r.sourceMesh];
    std::vector<double>& maxDelta = a->morphMaxDelta_[r.sourceMesh];
    maxDelta.assign(mesh.morphTargetCount, 0.0);
    for (size_t t = 0; t < mesh.morphTargetCount; ++t)
      for (size_t v = 0; v < mesh.vertices.size(); ++v) {
        const gpu::MorphDelta& d = mesh.morphDeltas[t * mesh.vertices.size() + v];
        maxDelta[t] = std::max(maxDelta[t], glm::length(glm::dvec3(d.px, d.py, d.pz)));
      }
  }
  for (size_t i = 0; i < a->regions_.size(); ++i)
    a->regionSpheres_.push_back(&a->spheres_[{a->regions_[i].sourceMesh, scene.skinnedObjects[i].skin}]);
  a->worldBounds_.resize(a->regions_.size());
  a->lodScale_.resize(a->regions_.size());
  const uint64_t limit = device.properties().limits.maxStorageBufferRange;
  const uint64_t boundsBytes = gpuBounds ? a->regions_.size() * SKIN_BOUNDS_UINTS * sizeof(uint32_t) : 16;
  const uint64_t rows = uint64_t(joints) * 3 + weightRows;
  for (auto [what, bytes] : {std::pair{"joint matrix", rows * sizeof(glm::vec4)},
                             std::pair{"skinned instance", a->regions_.size() * sizeof(gpu::SkinInstance)},
                             std::pair{"skinned bounds", boundsBytes}})
    if (bytes > limit)
      return makeError(ErrorCode::CapacityExceeded,
                       fmt::format("{} skinned instances: the {} buffer needs {:.1f} MiB, over this device's "
                                   "maxStorageBufferRange of {:.1f} MiB",
                                   a->regions_.size(), what, bytes / 1048576.0, limit / 1048576.0));
  const VkBufferUsageFlags ssbo = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  a->joints_ = gpu::Buffer(device, std::max<uint64_t>(3, rows) * sizeof(glm::vec4), ssbo,
                           gpu::MemoryUse::HostVisible);
  a->instances_ = gpu::Buffer(device, a->regions_.size() * sizeof(gpu::SkinInstance), ssbo,
                              gpu::MemoryUse::HostVisible);
  a->bounds_ = gpu::Buffer(device, boundsBytes, ssbo | VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::DeviceLocal);
  return a;
}

void AnimationState::evaluate(size_t first, size_t last, double time) {
  auto* rows = static_cast<glm::vec4*>(joints_.mapped());
  auto* records = static_cast<gpu::SkinInstance*>(instances_.mapped());
  Pose pose = rest_;
  for (size_t i = first; i < last; ++i) {
    const SkinnedObject& so = scene_.skinnedObjects[i];
    const GpuScene::SkinnedRegion& r = regions_[i];
    const Skin& skin = scene_.skins[so.skin];
    pose.locals = rest_.locals;
    pose.weights = rest_.weights;
    if (so.clip >= 0 && size_t(so.clip) < scene_.animations.size())
      sampleClip(scene_.animations[size_t(so.clip)], time + so.timeOffset, true, pose);
    // Morph weights (skinnedObjectMorphWeights' rule): the node's animated ones, else the mesh's defaults.
    double morphReach = 0.0;  // sum |w_t| max_v |delta_t,v|: no vertex moves farther than this from its base
    if (r.morphTargets > 0) {
      const Mesh& mesh = scene_.meshes[r.sourceMesh];
      const std::vector<double>& animated = pose.weights[size_t(so.morphNode)];
      const std::vector<double>& maxDelta = morphMaxDelta_.at(r.sourceMesh);
      float* w = &rows[morphWeightRow_[i]].x;
      for (uint32_t t = 0; t < (r.morphTargets + 3) / 4 * 4; ++t) {
        double weight = 0.0;
        if (t < animated.size() && t < r.morphTargets)
          weight = animated[t];
        else if (t < mesh.morphWeights.size())
          weight = mesh.morphWeights[t];
        w[t] = float(weight);
        if (t < r.morphTargets) morphReach += std::abs(double(float(weight))) * maxDelta[t];
      }
    }
    const std::vector<glm::dmat4> joints = jointMatrices(skin, globalMatrices(scene_.nodes, pose));
    double scale = 0.0;
    for (size_t j = 0; j < joints.size(); ++j) {
      const glm::mat4 m(joints[j]);
      for (int row = 0; row < 3; ++row)
        rows[3 * (firstJoint_[i] + j) + size_t(row)] = glm::vec4(m[0][row], m[1][row], m[2][row], m[3][row]);
      scale = std::max(scale, maxScaleOf(joints[j]));
    }
    glm::dvec4 sphere;
    if (morphReach > 0.0) {
      // Each morphed vertex lies within morphReach of its base position, so within each influencing joint's
      // sphere widened by it: skinnedBoundsSphere's proof then holds for the morphed vertices unchanged.
      std::vector<glm::dvec4> widened = *regionSpheres_[i];
      for (glm::dvec4& s : widened)
        if (s.w >= 0.0) s.w += morphReach;
      sphere = skinnedBoundsSphere(widened, joints);
    } else {
      sphere = skinnedBoundsSphere(*regionSpheres_[i], joints);
    }
    if (!(sphere.w >= 0.0) || !std::isfinite(sphere.w)) sphere = glm::dvec4(0.0, 0.0, 0.0, 0.0);
    gpu::SkinInstance& rec = records[i];
    rec.sourceVertex = r.sourceVertex;
    rec.skinVertex = r.skinVertex;
    rec.vertexCount = r.vertexCount;
    rec.sourceExtra = r.sourceExtra;
    rec.firstJoint = firstJoint_[i];
    rec.meshSlot = r.meshSlot;
    rec.sourceMesh = r.sourceMesh;
    rec.lodScale = float(scale);
    rec.bounds = glm::vec4(sphere);
    rec.firstMorphDelta = r.firstMorphDelta;
    rec.morphTargets = r.morphTargets;
    rec.morphWeightRow = morphWeightRow_[i];
    rec.morphPad = 0;
    const double placementScale = maxScaleOf(so.placement);
    worldBounds_[i] = glm::dvec4(glm::dvec3(so.placement * glm::dvec4(glm::dvec3(sphere), 1.0)),
                                 sphere.w * placementScale);
    lodScale_[i] = scale * placementScale;
  }
}

bool AnimationState::update(double time) {
  if (evaluated_ && time == lastTime_) return false;
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = regions_.size();
  const size_t threads = n < 256 ? 1 : std::min<size_t>(std::max(1u, std::thread::hardware_concurrency()), 16);
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t)
    pool.emplace_back([this, t, n, threads, time] { evaluate(n * t / threads, n * (t + 1) / threads, time); });
  evaluate(0, n / threads, time);
  for (std::thread& th : pool) th.join();
  evaluated_ = true;
  lastTime_ = time;
  lastUpdateMs_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return true;
}

bool AnimationState::skinnedBounds(uint32_t object, glm::dvec4* worldSphere, double* lodScale) const {
  if (object >= regionOfObject_.size() || regionOfObject_[object] < 0) return false;
  *worldSphere = worldBounds_[size_t(regionOfObject_[object])];
  *lodScale = lodScale_[size_t(regionOfObject_[object])];
  return true;
}

}  // namespace visbuf
