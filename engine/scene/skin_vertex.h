// Per-vertex skinning data of an animated mesh: up to 8 joint influences (glTF JOINTS_0 / WEIGHTS_0 and
// JOINTS_1 / WEIGHTS_1). Stored parallel to Mesh::vertices (Mesh::skinVertices) and in packs (section
// "skinVertices"); the skinning pass reads it as-is.
//
// One fixed 8-slot record for every skinned vertex, rather than the 4-slot record plus a second stream only for
// the meshes that need more: every reader (the skinning shader, the CPU reference skinning in animation.cpp, the
// joint-reach bounds, the pack section, vertex deduplication in buildMesh) stays one code path over one array
// with no per-mesh stream offsets or "has a second stream" flags to get wrong, and a vertex's influences compare
// byte for byte in one place. The cost is 24 more bytes per skinned vertex, and only skinned vertices carry
// it: in the scenes this renderer is for, skinned meshes are a few characters among millions of static
// triangles (a 10,000-vertex character: 240 KB more), and the skinning shader skips slots whose weight is 0, so
// 4-influence meshes do no extra joint fetches.
#pragma once

#include <cstdint>

namespace visbuf {

inline constexpr int kSkinInfluences = 8;  // joint slots per vertex

struct SkinVertex {
  uint16_t joints[kSkinInfluences];  // indices into the skin's joint list (Skin::joints), not node indices
  float weights[kSkinInfluences];    // each >= 0, finite, summing to 1 over all 8 (within float rounding);
                                     // slots with weight 0 have joint 0, so two vertices with the same
                                     // influences compare equal byte for byte
};
static_assert(sizeof(SkinVertex) == 48);

}  // namespace visbuf
