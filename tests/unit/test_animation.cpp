// Tests for skeletal animation (engine/scene/animation.h) and its import (importGltfScene: skins, clips,
// JOINTS_0 / WEIGHTS_0): interpolation against hand-computed values, hierarchy and joint matrices against
// composed double matrices, reference skinning, the conservative skinned bounds on real assets at many
// times, buildMesh's skin streams, and malformed files. Expected asset counts come from their JSON.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_assets.h"
#include "temp_dir_test.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/animation.h"
#include "visbuf/scene/generate.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using test::assetPath;

std::vector<double> sample(const AnimationSampler& s, AnimationPath path, double t) {
  std::vector<double> out(s.components);
  sampleSampler(s, path, t, out);
  return out;
}

void expectNear(const std::vector<double>& actual, const std::vector<double>& expected, double eps = 1e-12) {
  ASSERT_EQ(actual.size(), expected.size());
  for (size_t i = 0; i < actual.size(); ++i) EXPECT_NEAR(actual[i], expected[i], eps) << "component " << i;
}

// --- interpolation -----------------------------------------------------------------------------------------

// Welding with morph targets: two triangles of a quad listed with 6 vertices, the shared edge's two vertices
// duplicated exactly. buildMesh merges the duplicates only while their deltas agree too; after welding and the
// fetch reorder every built vertex, found by its base position and normal, carries its own source deltas.
// Checked with 1 target and with 13 (past meshoptimizer's 16 remap streams, where the deltas are compared as a
// key).
TEST(MorphTargets, WeldingKeepsVerticesThatMoveApart) {
  for (const size_t targets : {size_t{1}, size_t{13}}) {
    for (const bool split : {false, true}) {
      SCOPED_TRACE(::testing::Message() << targets << " targets, " << (split ? "split" : "shared") << " edge");
      MeshSource src;
      src.name = "quad";
      src.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};
      src.normals.assign(6, glm::vec3(0, 0, 1));
      src.indices = {0, 1, 2, 3, 4, 5};
      for (size_t t = 0; t < targets; ++t) {
        MeshSource::MorphTarget target;
        for (size_t v = 0; v < 6; ++v) target.positions.push_back(glm::vec3(0.0f, 0.0f, 0.125f * float(t + 1)));
        target.normals.assign(6, glm::vec3(0.0f, 0.25f, 0.0f));
        if (split && t + 1 == targets) target.positions[3].z = -1.0f;  // vertex 3 leaves vertex 0 in the last target
        src.morphTargets.push_back(target);
      }
      src.morphWeights.assign(targets, 0.5f);
      auto mesh = buildMesh(src);
      ASSERT_TRUE(mesh.ok()) << mesh.error().message;
      EXPECT_EQ(mesh->vertices.size(), split ? 5u : 4u);
      ASSERT_EQ(mesh->morphTargetCount, targets);
      ASSERT_EQ(mesh->morphDeltas.size(), targets * mesh->vertices.size());
      EXPECT_EQ(mesh->morphWeights, std::vector<float>(targets, 0.5f));
      // Every source triangle corner's morphed position must be a corner of the built LOD 0.
      std::vector<double> weights(targets, 1.0);
      for (size_t i = 0; i < src.indices.size(); ++i) {
        glm::dvec3 want(src.positions[src.indices[i]]);
        for (size_t t = 0; t < targets; ++t) want += glm::dvec3(src.morphTargets[t].positions[src.indices[i]]);
        double best = INFINITY;
        for (uint32_t k = 0; k < mesh->lods[0].indexCount; ++k) {
          const MorphedVertex m = morphVertex(*mesh, mesh->indices[mesh->lods[0].firstIndex + k], weights);
          best = std::min(best, glm::length(m.position - want));
        }
        EXPECT_EQ(best, 0.0) << "source corner " << i;
      }
      // Normal deltas follow too: n + sum dn, renormalised.
      const MorphedVertex m0 = morphVertex(*mesh, 0, weights);
      EXPECT_NEAR(glm::length(m0.normal - glm::normalize(glm::dvec3(0.0, 0.25 * double(targets), 1.0))), 0.0, 1e-4);
    }
  }
}

TEST(AnimationSampling, LinearClampsOutsideTheKeys) {
  const AnimationSampler s{Interpolation::Linear, 3, {1.0f, 3.0f}, {0, 0, 0, 2, 4, -6}};
  expectNear(sample(s, AnimationPath::Translation, 1.5), {0.5, 1.0, -1.5});  // u = 0.25
  expectNear(sample(s, AnimationPath::Translation, 0.0), {0, 0, 0});         // before the first key
  expectNear(sample(s, AnimationPath::Translation, 1.0), {0, 0, 0});
  expectNear(sample(s, AnimationPath::Translation, 3.0), {2, 4, -6});
  expectNear(sample(s, AnimationPath::Translation, 9.0), {2, 4, -6});  // after the last key
}

TEST(AnimationSampling, StepHoldsTheLastKeyAtOrBeforeTheTime) {
  const AnimationSampler s{Interpolation::Step, 1, {0.0f, 1.0f, 2.0f}, {10, 20, 30}};
  expectNear(sample(s, AnimationPath::Weights, 0.99), {10});
  expectNear(sample(s, AnimationPath::Weights, 1.0), {20});
  expectNear(sample(s, AnimationPath::Weights, 1.5), {20});
  expectNear(sample(s, AnimationPath::Weights, 7.0), {30});
  expectNear(sample(s, AnimationPath::Weights, -1.0), {10});
}

// Identity to 90 degrees about z: slerp gives the rotation by 90u degrees, q = (0, 0, sin(45u deg), cos(45u
// deg)).
TEST(AnimationSampling, LinearRotationIsSlerpOnTheShortestArc) {
  const float h = 0.70710678f;
  AnimationSampler s{Interpolation::Linear, 4, {0.0f, 1.0f}, {0, 0, 0, 1, 0, 0, h, h}};
  expectNear(sample(s, AnimationPath::Rotation, 0.5), {0, 0, 0.38268343236508978, 0.92387953251128674}, 1e-7);
  expectNear(sample(s, AnimationPath::Rotation, 0.25), {0, 0, 0.19509032201612825, 0.98078528040323043},
             1e-7);
  // The same end rotation written as -q: still the short way round, not through 270 degrees.
  s.values = {0, 0, 0, 1, 0, 0, -h, -h};
  expectNear(sample(s, AnimationPath::Rotation, 0.5), {0, 0, 0.38268343236508978, 0.92387953251128674}, 1e-7);
  // Unnormalised keys come out normalised.
  s.values = {0, 0, 0, 2, 0, 0, 0, 3};
  expectNear(sample(s, AnimationPath::Rotation, 0.3), {0, 0, 0, 1});
}

// Hermite: p(u) = h00 v0 + h10 dt b0 + h01 v1 + h11 dt a1 with dt = 2, u = 0.25:
// h00 = 2u^3 - 3u^2 + 1 = 0.84375, h10 = u^3 - 2u^2 + u = 0.140625, h01 = -2u^3 + 3u^2 = 0.15625,
// h11 = u^3 - u^2 = -0.046875. v0 = 1, b0 = 3, v1 = 5, a1 = -1:
// 0.84375 + 0.140625 * 2 * 3 + 0.15625 * 5 + (-0.046875) * 2 * (-1) = 2.5625.
TEST(AnimationSampling, CubicSplineScalesTangentsByTheKeyInterval) {
  //                                                      a0  v0  b0  a1  v1  b1
  const AnimationSampler s{Interpolation::CubicSpline, 1, {0.0f, 2.0f}, {0, 1, 3, -1, 5, 0}};
  expectNear(sample(s, AnimationPath::Weights, 0.5), {2.5625});
  expectNear(sample(s, AnimationPath::Weights, 0.0), {1});
  expectNear(sample(s, AnimationPath::Weights, 2.0), {5});
  expectNear(sample(s, AnimationPath::Weights, -3.0), {1});  // clamps to values, never extrapolates tangents
  expectNear(sample(s, AnimationPath::Weights, 3.0), {5});
}

// Quaternion cubic spline with zero tangents, identity -> 90 degrees about z, u = 0.25: the blend
// 0.84375 (0,0,0,1) + 0.15625 (0,0,h,h) = (0, 0, 0.110485, 0.954235), normalised (0, 0, 0.115016, 0.993364).
TEST(AnimationSampling, CubicSplineRotationIsNormalised) {
  const float h = 0.70710678f;
  const AnimationSampler s{Interpolation::CubicSpline, 4, {0.0f, 1.0f}, {0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0,
                                                                         0, 0, 0, 0, 0, 0, h, h, 0, 0, 0, 0}};
  expectNear(sample(s, AnimationPath::Rotation, 0.25), {0, 0, 0.11501586620387409, 0.9933636547213576}, 1e-7);
  expectNear(sample(s, AnimationPath::Rotation, 0.5), {0, 0, 0.38268343236508978, 0.92387953251128674}, 1e-7);
}

TEST(AnimationSampling, LoopingWrapsTheClipTime) {
  AnimationClip clip;
  clip.samplers.push_back({Interpolation::Linear, 3, {0.0f, 2.0f}, {0, 0, 0, 2, 0, 0}});
  clip.channels.push_back({0, 1, AnimationPath::Translation});
  clip.duration = 2.0;
  EXPECT_DOUBLE_EQ(clipTime(clip, 5.0, true), 1.0);
  EXPECT_DOUBLE_EQ(clipTime(clip, -0.5, true), 1.5);
  EXPECT_DOUBLE_EQ(clipTime(clip, 5.0, false), 5.0);
  std::vector<SceneNode> nodes(2);
  nodes[1].parent = 0;
  nodes[1].rest.scale = {2.0, 2.0, 2.0};
  Pose pose = restPose(nodes);
  sampleClip(clip, 5.5, true, pose);  // clip time 1.5
  EXPECT_EQ(pose.locals[1].translation, glm::dvec3(1.5, 0.0, 0.0));
  EXPECT_EQ(pose.locals[1].scale, glm::dvec3(2.0));  // not animated: kept
  sampleClip(clip, 5.5, false, pose);                // clamped to the last key
  EXPECT_EQ(pose.locals[1].translation, glm::dvec3(2.0, 0.0, 0.0));
}

// --- hierarchy, joints, skinning
// -----------------------------------------------------------------------------

TEST(AnimationPose, GlobalMatricesComposeParentsFirstInAnyOrder) {
  // Node 0's parent is node 2 (listed after it); node 1 is a matrix node under node 0.
  std::vector<SceneNode> nodes(3);
  nodes[0].parent = 2;
  nodes[0].rest.translation = {1.0, 0.0, 0.0};
  nodes[0].rest.rotation = glm::angleAxis(glm::radians(90.0), glm::dvec3(0.0, 0.0, 1.0));
  nodes[1].parent = 0;
  nodes[1].hasMatrix = true;
  nodes[1].matrix = glm::scale(glm::dmat4(1.0), {1.0, 3.0, 1.0});
  nodes[2].rest.scale = {2.0, 2.0, 2.0};
  ASSERT_TRUE(validateNodes(nodes));
  const std::vector<glm::dmat4> g = globalMatrices(nodes, restPose(nodes));
  const glm::dmat4 expected0 = glm::scale(glm::dmat4(1.0), glm::dvec3(2.0)) *
                               glm::translate(glm::dmat4(1.0), {1.0, 0.0, 0.0}) *
                               glm::rotate(glm::dmat4(1.0), glm::radians(90.0), {0.0, 0.0, 1.0});
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      EXPECT_NEAR(g[0][c][r], expected0[c][r], 1e-15);
      EXPECT_NEAR(g[1][c][r], (expected0 * nodes[1].matrix)[c][r], 1e-15);
    }
  }
  // A point on node 1's y axis: scaled by 3 (node 1), rotated to -x (node 0), moved by 1, scaled by 2.
  const glm::dvec3 p(g[1] * glm::dvec4(0.0, 1.0, 0.0, 1.0));
  EXPECT_NEAR(glm::length(p - glm::dvec3(2.0 * (1.0 - 3.0), 0.0, 0.0)), 0.0, 1e-14);
}

TEST(AnimationPose, CyclesAndMissingParentsAreRejected) {
  std::vector<SceneNode> nodes(3);
  nodes[0].parent = 2;
  nodes[1].parent = 0;
  nodes[2].parent = 1;
  Status s = validateNodes(nodes);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("cycle"), std::string::npos) << s.error().message;
  nodes[2].parent = 7;
  s = validateNodes(nodes);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("parent 7 does not exist"), std::string::npos) << s.error().message;
}

TEST(AnimationPose, CameraRelativeJointMatricesKeepPrecisionFarAway) {
  std::vector<SceneNode> nodes(1);
  nodes[0].rest.translation = {1e7 + 0.125, -3e6 + 0.0625, 5.0};
  Skin skin{"s", {0}, {glm::translate(glm::dmat4(1.0), {0.0, 0.0, 1.0})}, -1};
  const auto globals = globalMatrices(nodes, restPose(nodes));
  const glm::dvec3 origin(1e7, -3e6, 0.0);
  const std::vector<glm::mat4> rel = jointMatricesRelative(skin, globals, origin);
  // Exact in float because the difference is small; the absolute float matrix would round 1e7 + 0.125.
  EXPECT_EQ(rel[0][3], glm::vec4(0.125f, 0.0625f, 6.0f, 1.0f));
  EXPECT_EQ(glm::mat3(rel[0]), glm::mat3(1.0f));
  EXPECT_NE(float(jointMatrices(skin, globals)[0][3].x) - 1e7f, 0.125f);
}

TEST(AnimationSkinning, BlendsJointMatricesAndTransformsNormalsByTheInverseTranspose) {
  const std::vector<glm::dmat4> joints = {glm::translate(glm::dmat4(1.0), {2.0, 0.0, 0.0}),
                                          glm::scale(glm::dmat4(1.0), {1.0, 4.0, 1.0})};
  const SkinVertex blend{{0, 1, 0, 0}, {0.25f, 0.75f, 0.0f, 0.0f}};
  // 0.25 (p + (2,0,0)) + 0.75 (x, 4y, z) at p = (1,1,1): (1.5, 3.25, 1).
  EXPECT_NEAR(glm::length(skinPosition({1.0, 1.0, 1.0}, blend, joints) - glm::dvec3(1.5, 3.25, 1.0)), 0.0,
              1e-15);
  // Blended 3x3 = diag(1, 3.25, 1): a 45-degree normal in xy goes to normalize(1, 1/3.25, 0).
  const glm::dvec3 n = skinNormal(glm::normalize(glm::dvec3(1.0, 1.0, 0.0)), blend, joints);
  EXPECT_NEAR(glm::length(n - glm::normalize(glm::dvec3(1.0, 1.0 / 3.25, 0.0))), 0.0, 1e-15);
  // A mirroring joint keeps the normal's orientation consistent with the inverse-transpose.
  const std::vector<glm::dmat4> mirror = {glm::scale(glm::dmat4(1.0), {-1.0, 1.0, 1.0})};
  const SkinVertex one{{0, 0, 0, 0}, {1.0f, 0.0f, 0.0f, 0.0f}};
  EXPECT_NEAR(glm::length(skinNormal({1.0, 0.0, 0.0}, one, mirror) - glm::dvec3(-1.0, 0.0, 0.0)), 0.0, 1e-15);
}

// --- meshes ------------------------------------------------------------------------------------------------

TEST(AnimationMesh, BuildMeshKeepsSkinStreamsParallelAndDedupsOnThem) {
  // Two triangles sharing an edge; the shared corners are duplicated, one pair with identical skin data (it
  // merges), one pair with different joints (it must not).
  MeshSource src;
  src.name = "quad";
  src.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  src.normals.assign(6, glm::vec3(0, 0, 1));
  src.indices = {0, 1, 2, 3, 4, 5};
  src.joints = {{0, 0, 0, 0}, {1, 0, 0, 0}, {2, 0, 0, 0}, {1, 0, 0, 0}, {3, 0, 0, 0}, {4, 0, 0, 0}};
  src.weights.assign(6, glm::vec4(1, 0, 0, 0));
  Result<Mesh> mesh = buildMesh(src);
  ASSERT_TRUE(mesh) << mesh.error().message;
  EXPECT_EQ(mesh->vertices.size(), 5u);  // vertex 3 merged into 1; vertex 5 kept apart from 2
  ASSERT_EQ(mesh->skinVertices.size(), mesh->vertices.size());
  // Every output vertex still carries the joint of a source vertex at the same position.
  for (size_t v = 0; v < mesh->vertices.size(); ++v) {
    bool found = false;
    for (size_t s = 0; s < src.positions.size(); ++s)
      found |= mesh->position(uint32_t(v)) == src.positions[s] &&
               mesh->skinVertices[v].joints[0] == src.joints[s].x;
    EXPECT_TRUE(found) << "vertex " << v;
  }
  src.weights[2] = glm::vec4(-1, 0, 0, 0);
  EXPECT_FALSE(buildMesh(src));
}

// --- assets ------------------------------------------------------------------------------------------------

struct AssetCounts {
  const char* path;
  size_t nodes, joints, clips, channelsPerClip;
};

void expectCounts(const AssetCounts& a) {
  const fs::path path = assetPath(a.path);
  REQUIRE_ASSET(path);
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->nodes.size(), a.nodes);
  ASSERT_EQ(s->skins.size(), 1u);
  EXPECT_EQ(s->skins[0].joints.size(), a.joints);
  ASSERT_EQ(s->animations.size(), a.clips);
  for (const AnimationClip& c : s->animations) EXPECT_EQ(c.channels.size(), a.channelsPerClip) << c.name;
  ASSERT_EQ(s->instances.size(), 1u);
  EXPECT_EQ(s->instances[0].skin, 0);
  const MeshSource& m = s->meshes[s->instances[0].mesh].source;
  ASSERT_EQ(m.joints.size(), m.positions.size());
  ASSERT_EQ(m.weights.size(), m.positions.size());
  for (size_t v = 0; v < m.weights.size(); ++v) {
    const glm::vec4 w = m.weights[v];
    EXPECT_NEAR(w.x + w.y + w.z + w.w, 1.0f, 1e-6f) << "vertex " << v;
    for (int i = 0; i < 4; ++i) {
      if (w[i] > 0.0f) {
        EXPECT_LT(m.joints[v][i], a.joints) << "vertex " << v;
      }
    }
  }
}

// Counts from the files' JSON: nodes, skin joints, animations, channels per animation.
TEST(AnimationImport, CesiumMan) { expectCounts({"CesiumMan/glTF/CesiumMan.gltf", 22, 19, 1, 57}); }
TEST(AnimationImport, Fox) { expectCounts({"Fox/glTF/Fox.gltf", 26, 24, 3, 21}); }
TEST(AnimationImport, RiggedFigure) { expectCounts({"RiggedFigure/glTF/RiggedFigure.gltf", 22, 19, 1, 57}); }
TEST(AnimationImport, RiggedSimple) { expectCounts({"RiggedSimple/glTF/RiggedSimple.gltf", 5, 2, 1, 3}); }

TEST(AnimationImport, FoxWithoutNormalsOrIndicesGetsGeneratedNormals) {
  const fs::path path = assetPath("Fox/glTF-Binary/Fox.glb");
  REQUIRE_ASSET(path);
  Result<ImportedScene> s = importGltfScene(path.string());
  ASSERT_TRUE(s) << s.error().message;
  const MeshSource& m = s->meshes[0].source;
  EXPECT_EQ(m.positions.size(), 1728u);  // non-indexed: 576 triangles x 3
  EXPECT_EQ(m.indices.size(), 1728u);
  for (const glm::vec3& n : m.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
  EXPECT_EQ(s->animations[0].name, "Survey");
  EXPECT_EQ(s->animations[1].name, "Walk");
  EXPECT_EQ(s->animations[2].name, "Run");
  EXPECT_NEAR(s->animations[1].duration, 0.7083333134651184, 1e-9);
}

// The rest pose evaluated through the node list equals the importer's instance transforms (two independent
// compositions of the same TRS data).
TEST(AnimationImport, RestPoseGlobalsMatchInstanceTransforms) {
  for (const char* relative :
       {"CesiumMan/glTF/CesiumMan.gltf", "Fox/glTF/Fox.gltf", "RiggedSimple/glTF/RiggedSimple.gltf"}) {
    SCOPED_TRACE(relative);
    const fs::path path = assetPath(relative);
    REQUIRE_ASSET(path);
    Result<ImportedScene> s = importGltfScene(path.string());
    ASSERT_TRUE(s) << s.error().message;
    const auto globals = globalMatrices(s->nodes, restPose(s->nodes));
    for (const ImportedInstance& inst : s->instances)
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
          EXPECT_NEAR(globals[size_t(inst.node)][c][r], inst.transform[c][r], 1e-12);
  }
}

// For files whose inverse bind matrices invert the rest pose of the joints relative to the mesh node (the
// mesh was bound where it stands), skinning at the rest pose reproduces the unskinned instance: sum_i w_i J_i
// p
// == node world * p (measured: within 1e-6 of the extent). Not RiggedSimple: its mesh node sits under an
// extra 90-degree "Armature" rotation that its inverse binds do not include, so by the glTF rule (the skinned
// node's transform is ignored) its skinned rest pose is rotated against the unskinned one (checked
// independently from the JSON: both joint matrices are the Z_UP rotation alone).
TEST(AnimationImport, RestPoseSkinningEqualsTheUnskinnedInstance) {
  for (const char* relative :
       {"CesiumMan/glTF/CesiumMan.gltf", "Fox/glTF/Fox.gltf", "RiggedFigure/glTF/RiggedFigure.gltf"}) {
    SCOPED_TRACE(relative);
    const fs::path path = assetPath(relative);
    REQUIRE_ASSET(path);
    Result<ImportedScene> s = importGltfScene(path.string());
    ASSERT_TRUE(s) << s.error().message;
    const ImportedInstance& inst = s->instances[0];
    const MeshSource& m = s->meshes[inst.mesh].source;
    const auto joints = jointMatrices(s->skins[0], globalMatrices(s->nodes, restPose(s->nodes)));
    double worst = 0.0, extent = 0.0;
    for (size_t v = 0; v < m.positions.size(); ++v) {
      const SkinVertex sv{{m.joints[v].x, m.joints[v].y, m.joints[v].z, m.joints[v].w},
                          {m.weights[v].x, m.weights[v].y, m.weights[v].z, m.weights[v].w}};
      const glm::dvec3 skinned = skinPosition(glm::dvec3(m.positions[v]), sv, joints);
      const glm::dvec3 unskinned(inst.transform * glm::dvec4(glm::dvec3(m.positions[v]), 1.0));
      worst = std::max(worst, glm::length(skinned - unskinned));
      extent = std::max(extent, glm::length(unskinned));
    }
    EXPECT_LT(worst, 1e-5 * extent) << "extent " << extent;
  }
}

// Every vertex skinned at 40 random times per clip (fixed seed) lies inside skinnedBoundsSphere(); the
// bound is also reported against the tightest sphere around the same centre.
TEST(AnimationBounds, SkinnedVerticesStayInsideTheBoundAtRandomTimes) {
  for (const char* relative :
       {"CesiumMan/glTF/CesiumMan.gltf", "Fox/glTF/Fox.gltf", "RiggedFigure/glTF/RiggedFigure.gltf"}) {
    SCOPED_TRACE(relative);
    const fs::path path = assetPath(relative);
    REQUIRE_ASSET(path);
    Result<ImportedScene> imported = importGltfScene(path.string());
    ASSERT_TRUE(imported) << imported.error().message;
    Result<Scene> scene = buildImportedScene(*imported);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->skinnedObjects.size(), 1u);
    const SkinnedObject& so = scene->skinnedObjects[0];
    const Mesh& mesh = scene->meshes[scene->objects[so.object].mesh];
    const Skin& skin = scene->skins[so.skin];
    ASSERT_EQ(mesh.skinVertices.size(), mesh.vertices.size());
    std::vector<glm::vec3> positions(mesh.vertices.size());
    for (size_t v = 0; v < positions.size(); ++v) positions[v] = mesh.position(uint32_t(v));
    const auto spheres = jointInfluenceSpheres(positions, mesh.skinVertices, skin.joints.size());
    Rng rng(42);
    double worstSlack = INFINITY, loosest = 0.0;
    for (const AnimationClip& clip : scene->animations) {
      for (int k = 0; k < 40; ++k) {
        const double t = rng.uniform(-0.2, clip.duration * 2.0 + 0.2);
        Pose pose = restPose(scene->nodes);
        sampleClip(clip, t, k % 2 == 0, pose);
        const auto joints = jointMatrices(skin, globalMatrices(scene->nodes, pose));
        const glm::dvec4 bound = skinnedBoundsSphere(spheres, joints);
        ASSERT_TRUE(std::isfinite(bound.w));
        double farthest = 0.0;
        for (size_t v = 0; v < positions.size(); ++v) {
          const double d = glm::length(skinPosition(glm::dvec3(positions[v]), mesh.skinVertices[v], joints) -
                                       glm::dvec3(bound));
          farthest = std::max(farthest, d);
          ASSERT_LE(d, bound.w) << clip.name << " t=" << t << " vertex " << v;
        }
        worstSlack = std::min(worstSlack, bound.w - farthest);
        loosest = std::max(loosest, bound.w / farthest);
      }
    }
    std::printf("[          ] %s: bound radius / farthest vertex <= %.2f\n", relative, loosest);
    EXPECT_GE(worstSlack, 0.0);
  }
}

// --- malformed files ---------------------------------------------------------------------------------------

// A two-joint skinned triangle with a translation animation, written as .gltf with an embedded buffer.
class AnimationSynthetic : public test::TempDirTest {
 protected:
  static std::string base64(const std::string& bytes) {
    static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
      const size_t n = std::min<size_t>(3, bytes.size() - i);  // n bytes give n + 1 characters, then '='
      uint32_t t = 0;
      for (size_t k = 0; k < 3; ++k) t = (t << 8) | (k < n ? uint8_t(bytes[i + k]) : 0u);
      for (size_t k = 0; k < 4; ++k) out += k <= n ? kAlphabet[(t >> (18 - 6 * k)) & 63] : '=';
    }
    return out;
  }
  template <typename T>
  static void add(std::string& bytes, std::initializer_list<T> values) {
    for (T v : values) bytes.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  // Buffer views: 0 positions (36 B), 1 joints (u16 x 4 x 3 = 24 B), 2 weights (48 B), 3 inverse binds
  // (128 B), 4 times (12 B), 5 translations (36 B).
  json document(const std::vector<float>& times = {0.0f, 1.0f, 2.0f}, float weight2 = 2.0f) {
    std::string bytes;
    add<float>(bytes, {0, 0, 0, 1, 0, 0, 0, 1, 0});
    add<uint16_t>(bytes, {0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0});
    add<float>(bytes, {1, 0, 0, 0, 0.5f, 0.5f, 0, 0, weight2, 0, 0, 0});
    add<float>(bytes, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
    add<float>(bytes, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 1});  // translate(-1, 0, 0)
    add<float>(bytes, {times[0], times[1], times[2]});
    add<float>(bytes, {1, 0, 0, 1, 1, 0, 1, 0, 0});
    std::vector<json> views;
    size_t at = 0;
    for (size_t len : {36, 24, 48, 128, 12, 36}) {
      views.push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", len}});
      at += len;
    }
    json acc = json::array();
    acc.push_back({{"bufferView", 0},
                   {"componentType", 5126},
                   {"count", 3},
                   {"type", "VEC3"},
                   {"min", {0, 0, 0}},
                   {"max", {1, 1, 0}}});
    acc.push_back({{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "VEC4"}});
    acc.push_back({{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC4"}});
    acc.push_back({{"bufferView", 3}, {"componentType", 5126}, {"count", 2}, {"type", "MAT4"}});
    acc.push_back({{"bufferView", 4}, {"componentType", 5126}, {"count", 3}, {"type", "SCALAR"}});
    acc.push_back({{"bufferView", 5}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}});
    return {
        {"asset", {{"version", "2.0"}}},
        {"buffers",
         {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + base64(bytes)}}}},
        {"bufferViews", views},
        {"accessors", acc},
        {"meshes",
         {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"JOINTS_0", 1}, {"WEIGHTS_0", 2}}}}}}}}},
        {"skins", {{{"joints", {2, 3}}, {"inverseBindMatrices", 3}, {"skeleton", 2}, {"name", "rig"}}}},
        {"animations",
         {{{"name", "slide"},
           {"samplers", {{{"input", 4}, {"output", 5}}}},
           {"channels", {{{"sampler", 0}, {"target", {{"node", 3}, {"path", "translation"}}}}}}}}},
        {"nodes",
         {{{"children", {1, 2}}},
          {{"mesh", 0}, {"skin", 0}},
          {{"children", {3}}},
          {{"translation", {1, 0, 0}}}}},
        {"scenes", {{{"nodes", {0}}}}},
        {"scene", 0}};
  }
  Result<ImportedScene> import(const json& doc) {
    const fs::path path = dir_ / "skinned.gltf";
    std::ofstream(path) << doc.dump();
    return importGltfScene(path.string());
  }
  static ::testing::AssertionResult rejected(const Result<ImportedScene>& r, const std::string& text) {
    if (r) return ::testing::AssertionFailure() << "import succeeded; expected '" << text << "'";
    if (r.error().code != ErrorCode::MalformedInput || r.error().message.find(text) == std::string::npos)
      return ::testing::AssertionFailure() << errorCodeName(r.error().code) << ": " << r.error().message;
    return ::testing::AssertionSuccess();
  }
};

TEST_F(AnimationSynthetic, ImportsSkinClipAndRenormalisedWeights) {
  Result<ImportedScene> s = import(document());
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_EQ(s->nodes.size(), 4u);
  EXPECT_EQ(s->nodes[3].parent, 2);
  ASSERT_EQ(s->skins.size(), 1u);
  EXPECT_EQ(s->skins[0].name, "rig");
  EXPECT_EQ(s->skins[0].skeleton, 2);
  EXPECT_EQ(s->skins[0].inverseBindMatrices[1][3], glm::dvec4(-1.0, 0.0, 0.0, 1.0));
  ASSERT_EQ(s->instances.size(), 1u);
  EXPECT_EQ(s->instances[0].skin, 0);
  const MeshSource& m = s->meshes[0].source;
  EXPECT_EQ(m.weights[2], glm::vec4(1, 0, 0, 0));  // (2, 0, 0, 0) renormalised
  EXPECT_EQ(m.joints[2], glm::u16vec4(1, 0, 0, 0));
  ASSERT_EQ(s->animations.size(), 1u);
  EXPECT_EQ(s->animations[0].duration, 2.0);
  // At the rest pose J_1 = T(1,0,0) * T(-1,0,0) = identity: skinning leaves the vertices in place; at t = 1
  // joint 1 has moved to (1,1,0): vertex 2 (joint 1 only) moves by (0,1,0), vertex 1 (half) by (0,0.5,0).
  Pose pose = restPose(s->nodes);
  sampleClip(s->animations[0], 1.0, false, pose);
  const auto joints = jointMatrices(s->skins[0], globalMatrices(s->nodes, pose));
  auto skinned = [&](size_t v) {
    const SkinVertex sv{{m.joints[v].x, m.joints[v].y, m.joints[v].z, m.joints[v].w},
                        {m.weights[v].x, m.weights[v].y, m.weights[v].z, m.weights[v].w}};
    return skinPosition(glm::dvec3(m.positions[v]), sv, joints);
  };
  EXPECT_EQ(skinned(0), glm::dvec3(0, 0, 0));
  EXPECT_EQ(skinned(1), glm::dvec3(1, 0.5, 0));
  EXPECT_EQ(skinned(2), glm::dvec3(0, 2, 0));
}

TEST_F(AnimationSynthetic, BadJointIndex) {
  json doc = document();
  doc["skins"][0]["joints"] = {2};  // vertices use joint index 1
  doc["skins"][0].erase("inverseBindMatrices");
  EXPECT_TRUE(rejected(import(doc), "uses joint index 1, not below the skin's joint count 1"));
}

TEST_F(AnimationSynthetic, MissingJointNode) {
  json doc = document();
  doc["skins"][0]["joints"] = {2, 9};
  EXPECT_TRUE(rejected(import(doc), "skins[0].joints[1]: 9 is not a valid index; nodes has 4 entries"));
}

TEST_F(AnimationSynthetic, TooFewInverseBindMatrices) {
  json doc = document();
  doc["accessors"][3]["count"] = 1;
  EXPECT_TRUE(
      rejected(import(doc), "accessor 3 (inverseBindMatrices): count 1 is less than the joint count 2"));
}

TEST_F(AnimationSynthetic, NonIncreasingTimes) {
  EXPECT_TRUE(
      rejected(import(document({0.0f, 1.0f, 1.0f})),
               "animation 0 'slide' sampler 0 input accessor 4: times are not strictly increasing (key 2"));
  EXPECT_TRUE(rejected(import(document({0.0f, NAN, 2.0f})), "input accessor 4: time 1 is not finite"));
}

TEST_F(AnimationSynthetic, WrongOutputCount) {
  json doc = document();
  doc["accessors"][5]["count"] = 2;
  EXPECT_TRUE(rejected(import(doc), "output accessor 5: 2 elements for 3 keys; LINEAR needs 1 per key"));
  doc = document();
  doc["animations"][0]["samplers"][0]["interpolation"] = "CUBICSPLINE";  // needs 9 elements for 3 keys
  EXPECT_TRUE(rejected(import(doc), "output accessor 5: 3 elements for 3 keys; CUBICSPLINE needs 3 per key"));
  doc["animations"][0]["samplers"][0]["interpolation"] = "SMOOTH";
  EXPECT_TRUE(rejected(import(doc), "unknown interpolation 'SMOOTH'"));
}

TEST_F(AnimationSynthetic, BadWeights) {
  EXPECT_TRUE(rejected(import(document({0.0f, 1.0f, 2.0f}, NAN)),
                       "(WEIGHTS_0): vertex 2 has a negative or non-finite weight"));
  EXPECT_TRUE(
      rejected(import(document({0.0f, 1.0f, 2.0f}, -0.5f)), "vertex 2 has a negative or non-finite weight"));
  // All-zero weights import with a warning; the vertex follows its first slot.
  const fs::path path = dir_ / "zero.gltf";
  std::ofstream(path) << document({0.0f, 1.0f, 2.0f}, 0.0f).dump();
  GltfImportReport report;
  Result<ImportedScene> s = importGltfScene(path.string(), {}, &report);
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->meshes[0].source.weights[2], glm::vec4(1, 0, 0, 0));
  bool warned = false;
  for (const std::string& w : report.warnings) warned |= w.find("all-zero weights") != std::string::npos;
  EXPECT_TRUE(warned);
}

TEST_F(AnimationSynthetic, AnimatedMatrixNodeAndSharedChild) {
  json doc = document();
  doc["nodes"][3] = {{"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1}}};
  EXPECT_TRUE(rejected(import(doc), "channel 0: target node 3 has a matrix"));
  doc = document();
  doc["nodes"][1]["children"] = {3};  // node 3 now has parents 1 and 2
  EXPECT_TRUE(rejected(import(doc), "child node 3 already has parent node"));
}

}  // namespace
}  // namespace visbuf
