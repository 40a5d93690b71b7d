// Tests for what a glTF import may ask for before it decodes it (engine/asset/gltf_budget.cpp): morph targets
// that share an accessor are decoded once (a budget far below one copy per target suffices, and the result is
// the hand-computed sum of the weights); primitives that share a large accessor are refused up front naming
// GltfImportOptions::maxMemoryBytes; mesh instances beyond GltfImportOptions::maxInstances are refused naming it.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "gltf_doc_builder.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf {
namespace {

using nlohmann::json;
using test::DocBuilder;
using test::GltfImportTest;
using test::kFloat;
using test::kTriangle;
using test::kUShort;
using test::triangleMesh;

// An accessor of `count` VEC3 whose first three elements come from `values` (sparse), the rest zero.
int sparseVec3(DocBuilder& b, uint64_t count, const std::vector<glm::vec3>& values, int indexView) {
  std::vector<float> flat;
  for (const glm::vec3& v : values) flat.insert(flat.end(), {v.x, v.y, v.z});
  const int valueView = b.addView(flat);
  return b.addAccessor({{"componentType", kFloat},
                        {"count", count},
                        {"type", "VEC3"},
                        {"sparse",
                         {{"count", values.size()},
                          {"indices", {{"bufferView", indexView}, {"componentType", kUShort}}},
                          {"values", {{"bufferView", valueView}}}}}});
}

class GltfBudgetTest : public GltfImportTest {};

// 5,000 targets naming one delta accessor of 100,000 vertices: one decode (1.2 MB), not 5,000 (6 GB), so a
// 64 MiB budget is enough; every vertex moves by the sum of the weights times the shared delta.
TEST_F(GltfBudgetTest, MorphTargetsSharingAnAccessorAreDecodedOnce) {
  constexpr uint64_t kVertices = 100000;
  constexpr int kTargets = 5000;
  DocBuilder b;
  const int indexView = b.addView(std::vector<uint16_t>{0, 1, 2, 0});
  const int indices = b.addAccessor({{"bufferView", indexView}, {"componentType", kUShort}, {"count", 3}, {"type", "SCALAR"}});
  const int position = sparseVec3(b, kVertices, kTriangle, indexView);
  b.accessor(position)["min"] = {0, 0, 0};
  b.accessor(position)["max"] = {1, 1, 0};
  const int delta = sparseVec3(b, kVertices, {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}}, indexView);
  json meshes = triangleMesh(position, indices);
  meshes[0]["primitives"][0]["targets"] = json::array();
  for (int t = 0; t < kTargets; ++t) meshes[0]["primitives"][0]["targets"].push_back({{"POSITION", delta}});
  meshes[0]["weights"] = std::vector<double>(kTargets, 0.0004);  // sum 2.0
  GltfImportOptions options;
  options.maxMemoryBytes = uint64_t{64} << 20;
  auto mesh = importGltfMesh(write("morph.gltf", b.build(meshes, {{{"mesh", 0}}})), options);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  ASSERT_GE(mesh->positions.size(), 3u);
  for (int v = 0; v < 3; ++v) {
    EXPECT_FLOAT_EQ(mesh->positions[size_t(v)].x, kTriangle[size_t(v)].x);
    EXPECT_FLOAT_EQ(mesh->positions[size_t(v)].y, kTriangle[size_t(v)].y);
    EXPECT_NEAR(mesh->positions[size_t(v)].z, 2.0f, 1e-4f);
  }
}

// The same targets kept as deltas (a clip animates the node's weights): the output really holds 5,000 copies,
// charged before the first is made.
TEST_F(GltfBudgetTest, AnimatedMorphTargetsAreChargedUpFront) {
  DocBuilder b;
  const int indexView = b.addView(std::vector<uint16_t>{0, 1, 2, 0});
  const int indices = b.addAccessor({{"bufferView", indexView}, {"componentType", kUShort}, {"count", 3}, {"type", "SCALAR"}});
  const int position = sparseVec3(b, 100000, kTriangle, indexView);
  b.accessor(position)["min"] = {0, 0, 0};
  b.accessor(position)["max"] = {1, 1, 0};
  const int delta = sparseVec3(b, 100000, {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}}, indexView);
  const int time = b.addAccessor({{"componentType", kFloat}, {"count", 1}, {"type", "SCALAR"}, {"min", {0}}, {"max", {0}}});
  const int weights = b.addAccessor({{"componentType", kFloat}, {"count", 5000}, {"type", "SCALAR"}});
  json meshes = triangleMesh(position, indices);
  meshes[0]["primitives"][0]["targets"] = json::array();
  for (int t = 0; t < 5000; ++t) meshes[0]["primitives"][0]["targets"].push_back({{"POSITION", delta}});
  json doc = b.build(meshes, {{{"mesh", 0}}});
  doc["animations"] = {{{"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}}}},
                        {"samplers", {{{"input", time}, {"output", weights}}}}}};
  GltfImportOptions options;
  options.maxMemoryBytes = uint64_t{256} << 20;
  auto scene = importGltfScene(write("animated.gltf", doc), options);
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.error().code, ErrorCode::CapacityExceeded);
  EXPECT_NE(scene.error().message.find("5000 animated morph targets: needs 6000000000 more bytes"), std::string::npos)
      << scene.error().message;
  EXPECT_NE(scene.error().message.find("GltfImportOptions::maxMemoryBytes"), std::string::npos);
}

// 3,000 primitives naming one accessor of 2^20 vertices ask for 3,000 decoded copies: refused before the first.
TEST_F(GltfBudgetTest, PrimitivesSharingALargeAccessorAreRefusedUpFront) {
  DocBuilder b;
  b.addView(std::vector<float>{0.0f});  // (a buffer holds at least one byte)
  const int shared = b.addAccessor({{"componentType", kFloat}, {"count", 1 << 20}, {"type", "VEC3"},
                                    {"min", {0, 0, 0}}, {"max", {0, 0, 0}}});
  json meshes = json::array({{{"primitives", json::array()}}});
  for (int p = 0; p < 3000; ++p) meshes[0]["primitives"].push_back({{"attributes", {{"POSITION", shared}}}});
  auto mesh = importGltfMesh(write("shared.gltf", b.build(meshes, {{{"mesh", 0}}})));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::CapacityExceeded);
  EXPECT_NE(mesh.error().message.find("mesh 0: its 3000 primitives need about"), std::string::npos)
      << mesh.error().message;
  EXPECT_NE(mesh.error().message.find("GltfImportOptions::maxMemoryBytes"), std::string::npos);

  // Three of them fit: 3 x 2^20 vertices, each primitive's own copy.
  meshes[0]["primitives"] = json::array();
  for (int p = 0; p < 3; ++p) meshes[0]["primitives"].push_back({{"attributes", {{"POSITION", shared}}}});
  auto few = importGltfMesh(write("few.gltf", b.build(meshes, {{{"mesh", 0}}})));
  ASSERT_TRUE(few.ok()) << few.error().message;
  EXPECT_EQ(few->positions.size(), 3u << 20);
}

json instancedDoc(DocBuilder& b, uint64_t instances) {
  const int pos = b.addVec3(kTriangle);
  const int translation = b.addAccessor({{"componentType", kFloat}, {"count", instances}, {"type", "VEC3"}});
  json doc = b.build(triangleMesh(pos), {{{"mesh", 0},
                                          {"extensions", {{"EXT_mesh_gpu_instancing",
                                                           {{"attributes", {{"TRANSLATION", translation}}}}}}}}});
  doc["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  return doc;
}

TEST_F(GltfBudgetTest, InstancesWithinTheLimit) {
  GltfImportOptions options;
  options.maxInstances = 100;
  DocBuilder b;
  auto scene = importGltfScene(write("at.gltf", instancedDoc(b, 100)), options);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  EXPECT_EQ(scene->instances.size(), 100u);
  DocBuilder b2;
  auto mesh = importGltfMesh(write("at_mesh.gltf", instancedDoc(b2, 100)), options);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->indices.size(), 300u);
}

TEST_F(GltfBudgetTest, InstancesBeyondTheLimitAreRefusedNamingIt) {
  GltfImportOptions options;
  options.maxInstances = 100;
  for (bool sceneImport : {true, false}) {
    DocBuilder b;
    const std::string path = write("over.gltf", instancedDoc(b, 101));
    Error error{ErrorCode::InvalidArgument, {}};
    if (sceneImport) {
      auto r = importGltfScene(path, options);
      ASSERT_FALSE(r.ok());
      error = r.error();
    } else {
      auto r = importGltfMesh(path, options);
      ASSERT_FALSE(r.ok());
      error = r.error();
    }
    EXPECT_EQ(error.code, ErrorCode::CapacityExceeded);
    EXPECT_NE(error.message.find("101 instances pass the import's limit of 100 instances"), std::string::npos)
        << error.message;
    EXPECT_NE(error.message.find("GltfImportOptions::maxInstances"), std::string::npos);
  }
  // Plain nodes count too.
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  json nodes = json::array();
  json roots = json::array();
  for (int n = 0; n < 101; ++n) {
    nodes.push_back({{"mesh", 0}, {"translation", {n, 0, 0}}});
    roots.push_back(n);
  }
  auto scene = importGltfScene(write("nodes.gltf", b.build(triangleMesh(pos), nodes, {{{"nodes", roots}}})), options);
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.error().message.find("GltfImportOptions::maxInstances"), std::string::npos) << scene.error().message;
}

}  // namespace
}  // namespace visbuf
