// The CPU half of skinning: every frame, each skinned instance's pose is evaluated in double precision
// (scene/animation.h: clip sampling, node hierarchy, joint matrices), its conservative bounding sphere taken
// from the joints' reach (skinnedBoundsSphere), and the joint rows and instance records written to the
// host-visible buffers the skinning pass (passes/skin_pass.h) reads, with the morph weights of instances whose
// mesh has morph targets (after all joint rows; the joint-reach bound widened by the weighted delta reach). Exists only for scenes with skinned
// objects; a frame at the same animation time as the last one changes nothing (a paused animation is not
// re-skinned).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/gpu/resources.h"
#include "visbuf/scene/gpu_scene.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

class AnimationState {
 public:
  // nullptr when the scene has no skinned objects. gpuBounds: also allocate the skinning pass's bounds records
  // (SKIN_BOUNDS_UINTS per instance); the joint-reach spheres are computed either way (the forward path's CPU
  // culling uses them). CapacityExceeded when the joint rows (48 bytes per joint per instance) or the instance
  // records pass maxStorageBufferRange (lavapipe, 128 MiB: about 116,000 Foxes of 24 joints).
  static Result<std::unique_ptr<AnimationState>> create(gpu::Device& device, const Scene& scene,
                                                        const GpuScene& gpuScene, bool gpuBounds);

  // Evaluates every instance at `time` seconds and writes the buffers. Returns false, doing nothing, when
  // the poses are already those of `time`.
  bool update(double time);
  // update(time) would evaluate and rewrite the buffers.
  bool wouldUpdate(double time) const { return !evaluated_ || time != lastTime_; }

  uint32_t instanceCount() const { return uint32_t(regions_.size()); }
  uint32_t maxVertices() const { return maxVertices_; }
  uint64_t vertexCount() const { return vertexCount_; }
  double lastUpdateMs() const { return lastUpdateMs_; }
  const gpu::Buffer& joints() const { return joints_; }
  const gpu::Buffer& instances() const { return instances_; }
  const gpu::Buffer& bounds() const { return bounds_; }
  uint64_t bytes() const { return joints_.size() + instances_.size() + bounds_.size(); }

  // For the forward path's CPU culling and LOD: the world-space sphere of a skinned object's current pose
  // and the scale its LOD errors take; false for objects that are not skinned.
  bool skinnedBounds(uint32_t object, glm::dvec4* worldSphere, double* lodScale) const;

 private:
  AnimationState(const Scene& scene, const GpuScene& gpuScene) : scene_(scene), gpuScene_(gpuScene) {}
  void evaluate(size_t first, size_t last, double time);

  const Scene& scene_;
  const GpuScene& gpuScene_;
  std::vector<GpuScene::SkinnedRegion> regions_;
  std::vector<uint32_t> firstJoint_;                    // per region
  std::map<std::pair<uint32_t, uint32_t>, std::vector<glm::dvec4>> spheres_;  // (mesh, skin) -> per joint
  std::vector<const std::vector<glm::dvec4>*> regionSpheres_;
  std::map<uint32_t, std::vector<double>> morphMaxDelta_;  // mesh -> per target: largest |position delta|
  std::vector<uint32_t> morphWeightRow_;                   // per region: first row of its morph weights
  Pose rest_;
  std::vector<int32_t> regionOfObject_;
  std::vector<glm::dvec4> worldBounds_;
  std::vector<double> lodScale_;
  gpu::Buffer joints_, instances_, bounds_;
  uint32_t maxVertices_ = 0;
  uint64_t vertexCount_ = 0;
  bool evaluated_ = false;
  double lastTime_ = 0.0;
  double lastUpdateMs_ = 0.0;
};

}  // namespace visbuf
