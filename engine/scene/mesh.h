// CPU truth for one mesh: indexed triangle list plus its LOD chain.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/type_precision.hpp>

namespace visbuf {

// Geometry as imported or generated, before optimisation. Triangle list, counter-clockwise front faces.
struct MeshSource {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // same count as positions (generated when absent)
  std::vector<glm::vec2> uvs;      // empty or same count as positions
  std::vector<uint32_t> colors;    // empty or same count as positions, RGBA8 (R in low byte)
  std::vector<glm::vec2> uvs1;     // TEXCOORD_1: empty or same count as positions
  // Empty or same count as positions: xyz unit (along +u of TEXCOORD_0), w = +1 or -1 the handedness,
  // bitangent = cross(normal, xyz) * w; (0,0,0,0) for vertices that have none (the shader derives one).
  std::vector<glm::vec4> tangents;
  std::vector<uint32_t> indices;   // 3 per triangle, each < positions.size()
  // Skinning streams (glTF JOINTS_0 / WEIGHTS_0): both empty, or both the same count as positions.
  std::vector<glm::u16vec4> joints;  // indices into the skin's joint list; slots with weight 0 hold 0
  std::vector<glm::vec4> weights;    // each >= 0, finite, summing to 1 (with weights1, when present)
  // Influences 5..8 (glTF JOINTS_1 / WEIGHTS_1): both empty, or both the same count as joints; weights and
  // weights1 together sum to 1.
  std::vector<glm::u16vec4> joints1;
  std::vector<glm::vec4> weights1;
  // Morph targets (glTF mesh.primitives[].targets) kept for animation, not baked: each stream of a target is
  // empty (the target does not move that attribute) or the same count as positions, finite. Tangent deltas
  // move the tangent's xyz only. Every target of a mesh has the same streams present.
  struct MorphTarget {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<glm::vec3> tangents;
  };
  std::vector<MorphTarget> morphTargets;
  std::vector<float> morphWeights;  // default weights (node's, else mesh's), one per target: empty = all 0
};

}  // namespace visbuf
