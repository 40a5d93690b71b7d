// Skinning and animation data for test scenes (the pack tests' generated scene gets it, so the pack round
// trip, corruption and fuzz tests cover the animation sections), and a comparison of it.
#pragma once

#include <cstring>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "visbuf/scene/animation.h"
#include "visbuf/scene/scene.h"

namespace visbuf::test {

// Adds 4 nodes (one with a matrix), a 2-joint skin whose bind pose is the rest pose, skin vertices for mesh
// `mesh` (x < -0.3: joint 0, x > 0.3: joint 1, a 50/50 blend between), `object` as a skinned object, and two
// clips covering every interpolation and path. The mesh also gets two morph targets (distinct deltas per vertex
// and field, default weights 0.25 and -0.5) driven by node 3, whose weights the second clip animates.
inline void addTestAnimation(Scene& scene, uint32_t mesh, uint32_t object) {
  SceneNode root{
      "root", -1, {{0.0, 1.0, 0.0}, glm::dquat(1.0, 0.0, 0.0, 0.0), {1.0, 1.0, 1.0}}, false, glm::dmat4(1.0)};
  SceneNode hip{"hip",
                0,
                {{0.0, 0.0, 0.0}, glm::angleAxis(0.5, glm::dvec3(0.0, 1.0, 0.0)), {1.0, 1.0, 1.0}},
                false,
                glm::dmat4(1.0)};
  SceneNode knee{
      "knee", 1, {}, true, glm::scale(glm::translate(glm::dmat4(1.0), {0.0, -1.0, 0.0}), glm::dvec3(0.5))};
  SceneNode tip{
      "", 2, {{0.25, -1.0, 0.0}, glm::dquat(1.0, 0.0, 0.0, 0.0), {1.0, 2.0, 1.0}}, false, glm::dmat4(1.0)};
  scene.nodes = {root, hip, knee, tip};
  const std::vector<glm::dmat4> rest = globalMatrices(scene.nodes, restPose(scene.nodes));
  Skin skin{"legs", {1, 3}, {glm::inverse(rest[1]), glm::inverse(rest[3])}, 0};
  for (glm::dmat4& m : skin.inverseBindMatrices)
    m = glm::dmat4(glm::dvec4(m[0].x, m[0].y, m[0].z, 0.0), glm::dvec4(m[1].x, m[1].y, m[1].z, 0.0),
                   glm::dvec4(m[2].x, m[2].y, m[2].z, 0.0), glm::dvec4(m[3].x, m[3].y, m[3].z, 1.0));
  scene.skins = {skin};

  Mesh& m = scene.meshes[mesh];
  m.skinVertices.resize(m.vertices.size());
  for (size_t v = 0; v < m.vertices.size(); ++v) {
    const float x = m.vertices[v].px;
    SkinVertex& s = m.skinVertices[v];
    s = SkinVertex{{0, 0, 0, 0}, {1.0f, 0.0f, 0.0f, 0.0f}};
    if (x > 0.3f) s.joints[0] = 1;
    if (x >= -0.3f && x <= 0.3f) s = SkinVertex{{0, 1, 0, 0}, {0.5f, 0.5f, 0.0f, 0.0f}};
  }
  scene.skinnedObjects = {{object, 0}};
  scene.skinnedObjects[0].morphNode = 3;
  m.morphTargetCount = 2;
  m.morphDeltas.resize(2 * m.vertices.size());
  for (size_t i = 0; i < m.morphDeltas.size(); ++i) {
    const float f = 0.01f * float(i + 1);
    m.morphDeltas[i] = gpu::MorphDelta{f, -f, 0.5f * f, 0.0f, f, 0.0f, -f, 0.0f, 0.25f};
  }
  m.morphWeights = {0.25f, -0.5f};

  AnimationClip walk;
  walk.name = "walk";
  walk.samplers.push_back(
      {Interpolation::Linear, 3, {0.0f, 0.5f, 1.25f}, {0, 1, 0, 0, 1.5f, 0, 0, 1, 0.25f}});
  walk.samplers.push_back({Interpolation::Step, 3, {0.0f, 1.0f}, {1, 1, 1, 1.5f, 0.5f, 1}});
  walk.samplers.push_back(
      {Interpolation::CubicSpline,
       4,
       {0.25f, 2.0f},
       {0, 0, 0, 0, 0, 0,           0, 1,           0, 0.1f, 0, 0,  // key 0: in-tangent, value, out-tangent
        0, 0, 0, 0, 0, 0.70710678f, 0, 0.70710678f, 0, 0,    0, 0}});
  walk.channels = {
      {0, 0, AnimationPath::Translation}, {1, 1, AnimationPath::Scale}, {2, 1, AnimationPath::Rotation}};
  walk.duration = 2.0;
  AnimationClip blink;  // empty name, a weights channel
  blink.samplers.push_back({Interpolation::Linear, 2, {0.0f, 0.5f}, {0, 1, 1, 0}});
  blink.channels = {{0, 3, AnimationPath::Weights}};
  blink.duration = 0.5;
  scene.animations = {walk, blink};
}

inline void expectAnimationEqual(const Scene& a, const Scene& b) {
  EXPECT_TRUE(a.nodes == b.nodes);
  EXPECT_TRUE(a.skins == b.skins);
  EXPECT_TRUE(a.animations == b.animations);
  EXPECT_TRUE(a.skinnedObjects == b.skinnedObjects);
  EXPECT_TRUE(a.rigidObjects == b.rigidObjects);
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (size_t i = 0; i < a.meshes.size(); ++i) {
    const auto& x = a.meshes[i].skinVertices;
    const auto& y = b.meshes[i].skinVertices;
    ASSERT_EQ(x.size(), y.size()) << "mesh " << i;
    if (!x.empty()) {
      EXPECT_EQ(std::memcmp(x.data(), y.data(), x.size() * sizeof(SkinVertex)), 0) << "mesh " << i;
    }
    EXPECT_EQ(a.meshes[i].morphTargetCount, b.meshes[i].morphTargetCount) << "mesh " << i;
    EXPECT_EQ(a.meshes[i].morphWeights, b.meshes[i].morphWeights) << "mesh " << i;
    const auto& dx = a.meshes[i].morphDeltas;
    const auto& dy = b.meshes[i].morphDeltas;
    ASSERT_EQ(dx.size(), dy.size()) << "mesh " << i;
    if (!dx.empty()) {
      EXPECT_EQ(std::memcmp(dx.data(), dy.data(), dx.size() * sizeof(gpu::MorphDelta)), 0) << "mesh " << i;
    }
  }
}

}  // namespace visbuf::test
