// visbuf render --skin-check N: the skinning pass's output against the CPU's double-precision skinning, and
// its culling bounds against the vertices, for N skinned instances spread over the scene (read back after the
// last frame). The error that goes beside the skinning benchmark's times.
#pragma once

#include <cstdint>

#include <nlohmann/json.hpp>

#include "visbuf/render/renderer.h"

namespace visbuf::tools {

struct SkinCheck {
  uint32_t instances = 0;       // instances checked
  uint64_t vertices = 0;        // vertices checked
  double maxPositionError = 0;  // max |p_gpu - p_cpu| over the rest mesh's bounding radius
  double maxNormalError = 0;    // max |n_gpu - n_cpu| (unit vectors; octahedral 2 x 16 bits included)
  double maxTangentError = 0;   // the same for tangents (0 when the meshes have none)
  uint64_t outside = 0;         // vertices outside their instance's culling sphere (must be 0)
  double meanRadiusRatio = 0;   // mean culling radius / largest distance of the vertices from their AABB centre
};

// `time`: the animation time of the last frame rendered. samples >= 1.
SkinCheck checkSkinning(const Renderer& renderer, const Scene& scene, double time, uint32_t samples);
nlohmann::json skinCheckToJson(const SkinCheck& c);

}  // namespace visbuf::tools
