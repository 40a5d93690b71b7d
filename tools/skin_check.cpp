#include "skin_check.h"

#include <algorithm>
#include <cmath>

#include "visbuf/scene/animation.h"

namespace visbuf::tools {

SkinCheck checkSkinning(const Renderer& renderer, const Scene& scene, double time, uint32_t samples) {
  SkinCheck c;
  const size_t count = scene.skinnedObjects.size();
  if (count == 0) return c;
  samples = std::clamp<uint32_t>(samples, 1u, uint32_t(count));
  for (uint32_t k = 0; k < samples; ++k) {
    const uint32_t i = uint32_t(uint64_t(k) * count / samples);
    auto back = renderer.readSkinnedInstance(i);
    if (!back) continue;
    const SkinnedObject& so = scene.skinnedObjects[i];
    const Mesh& mesh = scene.meshes[scene.objects[so.object].mesh];
    const std::vector<glm::dmat4> joints = skinnedObjectJoints(scene, so, time);
    const std::vector<double> weights = so.morphNode >= 0 ? skinnedObjectMorphWeights(scene, so, time)
                                                          : std::vector<double>();
    const glm::dvec3 centre(back->bounds);
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (size_t v = 0; v < back->vertices.size(); ++v) {
      const gpu::SkinnedVertex& s = back->vertices[v];
      const MorphedVertex rest = morphVertex(mesh, uint32_t(v), weights);  // glTF: morph, then skin
      const SkinVertex& w = mesh.skinVertices[v];
      const glm::dvec3 p(s.px, s.py, s.pz);
      const glm::dvec3 want = skinPosition(rest.position, w, joints);
      c.maxPositionError = std::max(c.maxPositionError, glm::length(p - want) / mesh.boundsSphere.w);
      const glm::dvec3 n = skinNormal(rest.normal, w, joints);
      c.maxNormalError = std::max(c.maxNormalError, glm::length(glm::dvec3(octDecode(s.normal)) - n));
      if (!back->tangents.empty() && mesh.tangents[v].w != 0.0f) {
        const glm::dvec3 t = skinTangent(rest.tangent, w, joints);
        c.maxTangentError = std::max(c.maxTangentError, glm::length(glm::dvec3(octDecode(back->tangents[v])) - t));
      }
      c.outside += !(glm::length(p - centre) <= double(back->bounds.w));
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    double reach = 0.0;
    for (const gpu::SkinnedVertex& s : back->vertices)
      reach = std::max(reach, glm::length(glm::dvec3(s.px, s.py, s.pz) - 0.5 * (lo + hi)));
    c.meanRadiusRatio += back->bounds.w / std::max(reach, 1e-30);
    c.vertices += back->vertices.size();
    ++c.instances;
  }
  if (c.instances) c.meanRadiusRatio /= c.instances;
  return c;
}

nlohmann::json skinCheckToJson(const SkinCheck& c) {
  return {{"instances", c.instances},           {"vertices", c.vertices},
          {"maxPositionError", c.maxPositionError}, {"maxNormalError", c.maxNormalError},
          {"maxTangentError", c.maxTangentError},   {"outside", c.outside},
          {"meanRadiusRatio", c.meanRadiusRatio}};
}

}  // namespace visbuf::tools
