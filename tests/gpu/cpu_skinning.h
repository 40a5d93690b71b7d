// The CPU reference of the skinning pass for tests: a scene's skinned objects posed in double precision.
#pragma once

#include <cmath>

#include "visbuf/scene/animation.h"
#include "visbuf/scene/scene.h"

namespace visbuf::test {

// The scene at `time` with every skinned object replaced by a static copy of its mesh, morphed (morphVertex) and
// skinned on the CPU in double precision (animation.h), placed by its placement; no animation data left. Shares
// no code with the GPU path beyond the pose evaluation (clip sampling, joint matrices and morph weights).
inline Scene cpuSkinned(const Scene& animated, double time) {
  Scene s = animated;
  s.nodes.clear();
  s.skins.clear();
  s.animations.clear();
  s.skinnedObjects.clear();
  for (const SkinnedObject& so : animated.skinnedObjects) {
    const std::vector<glm::dmat4> joints = skinnedObjectJoints(animated, so, time);
    const std::vector<double> weights =
        so.morphNode >= 0 ? skinnedObjectMorphWeights(animated, so, time) : std::vector<double>();
    const Object& o = animated.objects[so.object];
    Mesh m = animated.meshes[o.mesh];
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (size_t v = 0; v < m.vertices.size(); ++v) {
      gpu::Vertex& vert = m.vertices[v];
      const MorphedVertex morphed = morphVertex(animated.meshes[o.mesh], uint32_t(v), weights);
      const glm::dvec3 p = skinPosition(morphed.position, m.skinVertices[v], joints);
      const glm::dvec3 n = skinNormal(morphed.normal, m.skinVertices[v], joints);
      vert.px = float(p.x);
      vert.py = float(p.y);
      vert.pz = float(p.z);
      vert.normal = octEncode(glm::vec3(n));
      if (!m.tangents.empty() && m.tangents[v].w != 0.0f) {
        const glm::dvec3 t = skinTangent(morphed.tangent, m.skinVertices[v], joints);
        m.tangents[v] = glm::vec4(glm::vec3(t), m.tangents[v].w);
      }
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    m.skinVertices.clear();
    m.morphTargetCount = 0;
    m.morphDeltas.clear();
    m.morphWeights.clear();
    m.boundsSphere = glm::vec4(glm::vec3(0.5 * (lo + hi)), float(0.5 * glm::length(hi - lo)) * 1.0001f);
    s.objects[so.object].mesh = uint32_t(s.meshes.size());
    s.objects[so.object].transform = so.placement;
    s.meshes.push_back(std::move(m));
  }
  return s;
}

}  // namespace visbuf::test
