// Per-vertex skinning data of an animated mesh: up to 4 joint influences. Stored parallel to Mesh::vertices
// (Mesh::skinVertices) and in packs (section "skinVertices"); the skinning pass reads it as-is.
#pragma once

#include <cstdint>

namespace visbuf {

struct SkinVertex {
  uint16_t joints[4];  // indices into the skin's joint list (Skin::joints), not node indices
  float weights[4];    // each >= 0, finite, summing to 1 (within float rounding); slots with weight 0 have
                       // joint 0, so two vertices with the same influences compare equal byte for byte
};
static_assert(sizeof(SkinVertex) == 24);

}  // namespace visbuf
