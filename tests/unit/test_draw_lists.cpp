// Draw-list routing (shaders/shared/types.h drawListOf, used by the cull shader and the CPU) and the
// transparency pass's back-to-front order, against tables written out by hand from the glTF rules.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "visbuf/passes/transparent_pass.h"
#include "visbuf/scene/gpu_scene.h"

using namespace visbuf;

TEST(DrawLists, RoutingFollowsAlphaModeSidednessAndWinding) {
  struct Case {
    uint32_t materialFlags;
    bool mirrored;
    uint32_t list;
  };
  const Case cases[] = {
      {0, false, DRAW_LIST_OPAQUE},
      {0, true, DRAW_LIST_OPAQUE_FLIPPED},
      {MATERIAL_FLAG_DOUBLE_SIDED, false, DRAW_LIST_OPAQUE_DOUBLE_SIDED},
      {MATERIAL_FLAG_DOUBLE_SIDED, true, DRAW_LIST_OPAQUE_DOUBLE_SIDED},  // no culling: winding irrelevant
      {MATERIAL_FLAG_MASK, false, DRAW_LIST_MASKED},
      {MATERIAL_FLAG_MASK, true, DRAW_LIST_MASKED_FLIPPED},
      {MATERIAL_FLAG_MASK | MATERIAL_FLAG_DOUBLE_SIDED, true, DRAW_LIST_MASKED_DOUBLE_SIDED},
      {MATERIAL_FLAG_BLEND, false, DRAW_LIST_NONE},
      {MATERIAL_FLAG_BLEND | MATERIAL_FLAG_DOUBLE_SIDED, true, DRAW_LIST_NONE},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(gpu::drawListOf(c.mirrored ? OBJECT_FLAG_FLIP_WINDING : 0u, c.materialFlags), c.list)
        << "material flags " << c.materialFlags << (c.mirrored ? " mirrored" : "");
  }
}

TEST(DrawLists, PackedObjectsCarryWindingAndList) {
  Scene s;
  Material mask;
  mask.alphaMode = AlphaMode::Mask;
  Material blend;
  blend.alphaMode = AlphaMode::Blend;
  s.materials = {Material{}, mask, blend};
  Object plain{glm::dmat4(1.0), 0, 0};
  Object mirrored{glm::scale(glm::dmat4(1.0), glm::dvec3(1.0, -2.0, 1.0)), 0, 1};  // det < 0
  Object rotated{glm::rotate(glm::dmat4(1.0), 2.0, glm::dvec3(1.0, 1.0, 0.0)), 0, 2};  // det > 0
  const gpu::ObjectData a = packObject(plain, s), b = packObject(mirrored, s), c = packObject(rotated, s);
  EXPECT_EQ(a.flags & OBJECT_FLAG_FLIP_WINDING, 0u);
  EXPECT_EQ(b.flags & OBJECT_FLAG_FLIP_WINDING, OBJECT_FLAG_FLIP_WINDING);
  EXPECT_EQ(c.flags & OBJECT_FLAG_FLIP_WINDING, 0u);
  EXPECT_EQ(gpu::objectDrawList(a.flags), uint32_t(DRAW_LIST_OPAQUE));
  EXPECT_EQ(gpu::objectDrawList(b.flags), uint32_t(DRAW_LIST_MASKED_FLIPPED));
  EXPECT_EQ(gpu::objectDrawList(c.flags), DRAW_LIST_NONE);
}

TEST(DrawLists, TransparentOrderIsBackToFrontAndStable) {
  std::vector<passes::TransparentDraw> d(5);
  const double depth[5] = {1.0, 7.5, -2.0, 7.5, 3.0};
  for (uint32_t i = 0; i < 5; ++i) {
    d[i].draw.objectId = i;
    d[i].viewDepth = depth[i];
  }
  passes::sortBackToFront(d);
  std::vector<uint32_t> order;
  for (const auto& t : d) order.push_back(t.draw.objectId);
  EXPECT_EQ(order, (std::vector<uint32_t>{1, 3, 4, 0, 2}));  // equal depths keep scene order
}
