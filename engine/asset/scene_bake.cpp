#include "visbuf/asset/scene_bake.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <optional>

#include "visbuf/asset/pack_geometry.h"

namespace visbuf {

int32_t firstClipMoving(const Scene& scene, int32_t node) {
  for (size_t c = 0; c < scene.animations.size(); ++c)
    for (const AnimationChannel& ch : scene.animations[c].channels) {
      if (ch.path == AnimationPath::Weights) continue;
      for (int32_t n = node; n >= 0 && size_t(n) < scene.nodes.size(); n = scene.nodes[size_t(n)].parent)
        if (uint32_t(n) == ch.node) return int32_t(c);
    }
  return -1;
}

Result<Scene> buildImportedScene(const ImportedScene& imported, const MeshBuildOptions& options,
                                 const BakeProgress& progress) {
  Scene scene;
  scene.name = imported.name;
  scene.pointLights = imported.pointLights;
  scene.cameras = imported.cameras;
  // Meshes build in parallel (oneTBB; tbb::global_control limits the threads); each result goes to its own slot,
  // so the scene, and the pack written from it, do not depend on the thread count or the schedule.
  const size_t count = imported.meshes.size();
  std::vector<std::optional<Result<Mesh>>> built(count);
  std::mutex progressMutex;
  size_t done = 0;
  tbb::parallel_for(size_t{0}, count, [&](size_t i) {
    Result<Mesh> mesh = buildMesh(imported.meshes[i].source, options);
    // Triangles rotated into the order the pack's index codec reproduces (same triangles and winding), so a
    // baked mesh survives the pack round trip bit for bit and loading a pack gives the in-memory bake's scene.
    if (mesh) pack::rotateTrianglesToCodecOrder(mesh->indices);
    built[i].emplace(std::move(mesh));
    if (progress) {
      // Serialised, with the count of meshes finished so far: callers see 1, 2, ..., total in order.
      const std::lock_guard<std::mutex> lock(progressMutex);
      progress(++done, count, imported.meshes[i].source.name);
    }
  });
  scene.meshes.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    Result<Mesh>& mesh = *built[i];
    if (!mesh) {
      return makeError(mesh.error().code, fmt::format("{}: mesh {} '{}': {}", imported.name, i,
                                                      imported.meshes[i].source.name, mesh.error().message));
    }
    scene.meshes.push_back(std::move(mesh.value()));
  }
  scene.materials = imported.materials;
  if (scene.materials.empty()) {
    Material m;
    m.name = "default";
    scene.materials.push_back(m);
  }
  scene.nodes = imported.nodes;
  scene.skins = imported.skins;
  scene.animations = imported.animations;
  scene.objects.reserve(imported.instances.size());
  for (const ImportedInstance& inst : imported.instances) {
    const uint32_t object = uint32_t(scene.objects.size());
    scene.objects.push_back({inst.transform, inst.mesh, inst.material});
    if (inst.skin >= 0) {
      SkinnedObject so{object, uint32_t(inst.skin)};
      if (inst.morphed) so.morphNode = inst.node;
      scene.skinnedObjects.push_back(so);
    } else if (inst.rigid && inst.node >= 0 && size_t(inst.node) < scene.nodes.size()) {
      const int32_t clip = firstClipMoving(scene, inst.node);
      if (clip < 0) continue;
      RigidObject ro{object, inst.node, clip};
      scene.objects.back().transform = rigidObjectStartTransform(scene, ro, inst.transform);
      scene.rigidObjects.push_back(ro);
    }
  }
  frameScene(scene);
  return scene;
}

glm::dvec4 sceneBounds(const Scene& scene) {
  if (scene.objects.empty()) return glm::dvec4(0.0);
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const Object& o : scene.objects) {
    const glm::dvec4 s = objectBoundsWorld(scene, o);
    lo = glm::min(lo, glm::dvec3(s) - s.w);
    hi = glm::max(hi, glm::dvec3(s) + s.w);
  }
  const glm::dvec3 centre = (lo + hi) * 0.5;
  double radius = 0.0;
  for (const Object& o : scene.objects) {
    const glm::dvec4 s = objectBoundsWorld(scene, o);
    radius = std::max(radius, glm::length(glm::dvec3(s) - centre) + s.w);
  }
  return {centre, radius};
}

void frameScene(Scene& scene) {
  const glm::dvec4 b = animatedSceneBounds(scene);
  const double radius = std::max(b.w, 1e-6);
  Camera& c = scene.defaultCamera;
  const double dist = radius / std::sin(c.fovY * 0.5) * 1.05;
  scene.anchor = glm::dvec3(b);
  c.target = glm::dvec3(b);
  c.position = c.target + glm::normalize(glm::dvec3(0.35, 0.3, 1.0)) * dist;
  c.nearPlane = std::max(1e-4, radius * 1e-3);
}

}  // namespace visbuf
