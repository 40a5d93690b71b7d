// Tests for importGltfMesh (engine/asset/gltf_import.h).
//
// Most tests write a tiny .gltf into a temporary folder (gltf_doc_builder.h: every byte of the input is visible in
// the test). The containers (.glb, EXT_meshopt_compression): test_gltf_container.cpp; the repository's sample
// assets: test_gltf_import_assets.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "gltf_doc_builder.h"
#include "mesh_source_checks.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf {
namespace {

using nlohmann::json;

using test::DocBuilder;
using test::expectValidMesh;
using test::expectVec3Near;
using test::geometricNormal;
using test::GltfImportTest;
using test::kFloat;
using test::kByte;
using test::kShort;
using test::kTriangle;
using test::kUByte;
using test::kUShort;
using test::triangleMesh;

// --------------------------------------------------------------------------------------------------------
// Topology

TEST_F(GltfImportTest, TriangleStripBecomesListAndDropsDegenerates) {
  DocBuilder b;
  const int pos = b.addVec3({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 2, 0}, {1, 2, 0}});
  // The repeated 3 stitches two strips: triangles (2,3,3) and (3,3,4) are degenerate and must go.
  const int idx = b.addIndices16({0, 1, 2, 3, 3, 4, 5});
  GltfImportReport report;
  auto mesh =
      importGltfMesh(write("strip.gltf", b.build(triangleMesh(pos, idx, 5), {{{"mesh", 0}}})), {}, &report);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectValidMesh(*mesh);
  // Even triangles keep their order, odd ones swap the first two vertices (glTF spec).
  EXPECT_EQ(mesh->indices, (std::vector<uint32_t>{0, 1, 2, 2, 1, 3, 3, 4, 5}));
  EXPECT_EQ(report.primitivesImported, 1u);
  EXPECT_EQ(mesh->name, "strip");
}

TEST_F(GltfImportTest, NonIndexedTriangleFanBecomesList) {
  DocBuilder b;
  const int pos = b.addVec3({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {-1, 1, 0}});
  auto mesh = importGltfMesh(write("fan.gltf", b.build(triangleMesh(pos, std::nullopt, 6), {{{"mesh", 0}}})));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectValidMesh(*mesh);
  EXPECT_EQ(mesh->indices, (std::vector<uint32_t>{1, 2, 0, 2, 3, 0, 3, 4, 0}));
  for (size_t t = 0; t < 3; ++t) expectVec3Near(geometricNormal(*mesh, t), {0, 0, 1});
  for (const glm::vec3& n : mesh->normals) expectVec3Near(n, {0, 0, 1});  // generated, counter-clockwise
}

TEST_F(GltfImportTest, NonIndexedTriangleGetsSequentialIndicesAndGeneratedNormals) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  GltfImportReport report;
  auto mesh = importGltfMesh(write("tri.gltf", b.build(triangleMesh(pos), {{{"mesh", 0}}})), {}, &report);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->indices, (std::vector<uint32_t>{0, 1, 2}));
  ASSERT_EQ(mesh->normals.size(), 3u);
  for (const glm::vec3& n : mesh->normals) expectVec3Near(n, {0, 0, 1});
  EXPECT_TRUE(mesh->uvs.empty());
  EXPECT_TRUE(mesh->colors.empty());
  EXPECT_TRUE(report.warnings.empty());
}

TEST_F(GltfImportTest, PointsAndLinesAreSkippedWithWarning) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  json meshes = json::array({{{"primitives",
                               {{{"attributes", {{"POSITION", pos}}}, {"mode", 0}},
                                {{"attributes", {{"POSITION", pos}}}, {"mode", 1}},
                                {{"attributes", {{"POSITION", pos}}}}}}}});
  GltfImportReport report;
  auto mesh = importGltfMesh(write("mixed.gltf", b.build(meshes, {{{"mesh", 0}}})), {}, &report);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->indices.size(), 3u);
  EXPECT_EQ(report.primitivesImported, 1u);
  EXPECT_EQ(report.primitivesSkipped, 2u);
  ASSERT_EQ(report.warnings.size(), 2u);
  EXPECT_NE(report.warnings[0].find("POINTS"), std::string::npos) << report.warnings[0];
  EXPECT_NE(report.warnings[1].find("LINES"), std::string::npos) << report.warnings[1];
}

TEST_F(GltfImportTest, LinesOnlyIsNoTriangleGeometry) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  auto mesh =
      importGltfMesh(write("lines.gltf", b.build(triangleMesh(pos, std::nullopt, 3), {{{"mesh", 0}}})));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(mesh.error().message.find("no triangle geometry"), std::string::npos) << mesh.error().message;
}

TEST_F(GltfImportTest, PrimitiveWithoutPositionIsSkipped) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  const int normal = b.addVec3({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}});
  json meshes = json::array(
      {{{"primitives", {{{"attributes", {{"NORMAL", normal}}}}, {{"attributes", {{"POSITION", pos}}}}}}}});
  GltfImportReport report;
  auto mesh = importGltfMesh(write("nopos.gltf", b.build(meshes, {{{"mesh", 0}}})), {}, &report);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(report.primitivesSkipped, 1u);
  ASSERT_FALSE(report.warnings.empty());
  EXPECT_NE(report.warnings[0].find("POSITION"), std::string::npos);
}

// --------------------------------------------------------------------------------------------------------
// Transforms

TEST_F(GltfImportTest, MatrixParentAndTrsChildInstanceOneMeshTwice) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  const int normal = b.addVec3({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}});
  const double s = std::sqrt(0.5);
  json nodes = {// Uniform scale 2, then translate by (10, 0, 0); column-major.
                {{"name", "parent"},
                 {"mesh", 0},
                 {"matrix", {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 10, 0, 0, 1}},
                 {"children", {1}}},
                // T(0,1,0) * R(90 degrees about +Z) * S(3).
                {{"name", "child"},
                 {"mesh", 0},
                 {"translation", {0, 1, 0}},
                 {"rotation", {0, 0, s, s}},
                 {"scale", {3, 3, 3}}}};
  GltfImportReport report;
  auto mesh = importGltfMesh(write("nodes.gltf", b.build(triangleMesh(pos, std::nullopt, 4, normal), nodes)),
                             {}, &report);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectValidMesh(*mesh);
  EXPECT_EQ(report.primitivesImported, 2u);
  ASSERT_EQ(mesh->positions.size(), 6u);
  // Parent: p -> 2p + (10,0,0).
  expectVec3Near(mesh->positions[0], {10, 0, 0});
  expectVec3Near(mesh->positions[1], {12, 0, 0});
  expectVec3Near(mesh->positions[2], {10, 2, 0});
  // Child: p -> parent(R(3p) + (0,1,0)), with R(x,y,z) = (-y,x,z).
  //   (0,0,0) -> (0,1,0) -> (10,2,0); (1,0,0) -> (0,4,0) -> (10,8,0); (0,1,0) -> (-3,1,0) -> (4,2,0).
  expectVec3Near(mesh->positions[3], {10, 2, 0});
  expectVec3Near(mesh->positions[4], {10, 8, 0});
  expectVec3Near(mesh->positions[5], {4, 2, 0});
  EXPECT_EQ(mesh->indices, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5}));
  for (const glm::vec3& n : mesh->normals) expectVec3Near(n, {0, 0, 1});
}

TEST_F(GltfImportTest, NonUniformScaleTransformsNormalsByInverseTranspose) {
  DocBuilder b;
  // Triangle in the plane y + z = 0, counter-clockwise around (0,1,1).
  const int pos = b.addVec3({{0, 0, 0}, {1, 0, 0}, {0, 1, -1}});
  const glm::vec3 n = glm::normalize(glm::vec3(0, 1, 1));
  const int normal = b.addVec3({n, n, n});
  json nodes = {{{"mesh", 0}, {"scale", {1, 4, 1}}}};
  auto mesh = importGltfMesh(write("scale.gltf", b.build(triangleMesh(pos, std::nullopt, 4, normal), nodes)));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  // inverse-transpose(diag(1,4,1)) * (0,1,1) ~ (0, 1/4, 1) ~ (0, 1, 4): the scaled triangle's true normal.
  const glm::vec3 expected = glm::normalize(glm::vec3(0, 1, 4));
  for (const glm::vec3& v : mesh->normals) expectVec3Near(v, expected);
  expectVec3Near(geometricNormal(*mesh, 0), expected);
}

TEST_F(GltfImportTest, NegativeDeterminantFlipsWinding) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  const int normal = b.addVec3({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}});
  json nodes = {
      {{"name", "mirrorX"}, {"mesh", 0}, {"scale", {-1, 1, 1}}, {"children", {1}}},
      // Mirror in Z relative to the parent: det(parent * child) = +1, no flip for this one.
      {{"name", "mirrorXZ"}, {"mesh", 0}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1}}},
      {{"name", "mirrorZ"}, {"mesh", 0}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1}}}};
  json scenes = {{{"nodes", {0, 2}}}};
  auto mesh = importGltfMesh(
      write("mirror.gltf", b.build(triangleMesh(pos, std::nullopt, 4, normal), nodes, scenes)));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectValidMesh(*mesh);
  ASSERT_EQ(mesh->indices.size(), 9u);
  EXPECT_EQ((std::vector<uint32_t>(mesh->indices.begin(), mesh->indices.begin() + 3)),
            (std::vector<uint32_t>{0, 2, 1}));  // mirrored: winding flipped
  EXPECT_EQ((std::vector<uint32_t>(mesh->indices.begin() + 3, mesh->indices.begin() + 6)),
            (std::vector<uint32_t>{3, 4, 5}));  // mirrored twice: unchanged
  // In every instance the counter-clockwise geometric normal agrees with the stored (transformed) normal.
  for (size_t t = 0; t < 3; ++t) {
    const glm::vec3 stored = mesh->normals[mesh->indices[3 * t]];
    EXPECT_GT(glm::dot(geometricNormal(*mesh, t), stored), 0.999f) << "triangle " << t;
  }
  expectVec3Near(mesh->normals[0], {0, 0, 1});   // X mirror keeps a +Z normal
  expectVec3Near(mesh->normals[6], {0, 0, -1});  // Z mirror turns it around
}

TEST_F(GltfImportTest, NonFiniteNodeTransformIsMalformed) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  // JSON cannot spell NaN, but composing finite matrices can produce one: world(0,0) = 1e308 * 1e308 +
  // 1e308 * -1e308 = inf - inf = NaN.
  json nodes = {
      {{"name", "parent"},
       {"matrix", {1e308, 0, 0, 0, 1e308, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}},
       {"children", {1}}},
      {{"name", "Foo"}, {"mesh", 0}, {"matrix", {1e308, -1e308, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}}}};
  auto mesh = importGltfMesh(write("nan.gltf", b.build(triangleMesh(pos), nodes)));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(mesh.error().message.find("node 1 'Foo': non-finite transform"), std::string::npos)
      << mesh.error().message;

  // A literal that overflows double is rejected while parsing.
  std::string text = b.build(triangleMesh(pos), {{{"mesh", 0}, {"translation", {0, 0, 0}}}}).dump();
  const size_t at = text.find("\"translation\":[0,0,0]");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 21, "\"translation\":[1e400,0,0]");
  auto overflow = importGltfMesh(writeText("overflow.gltf", text));
  ASSERT_FALSE(overflow.ok());
  EXPECT_EQ(overflow.error().code, ErrorCode::MalformedInput);
}

TEST_F(GltfImportTest, NaNPositionIsMalformed) {
  DocBuilder b;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const int pos = b.addFloats({0, 0, 0, 1, 0, 0, 0, nan, 0}, "VEC3", 3);
  auto mesh = importGltfMesh(write("nanpos.gltf", b.build(triangleMesh(pos), {{{"mesh", 0}}})));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(mesh.error().message.find("(POSITION): non-finite"), std::string::npos) << mesh.error().message;
}

TEST_F(GltfImportTest, NodeCycleIsMalformed) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  json nodes = {{{"mesh", 0}, {"children", {1}}}, {{"children", {0}}}};
  auto mesh = importGltfMesh(write("cycle.gltf", b.build(triangleMesh(pos), nodes)));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
}

TEST_F(GltfImportTest, NoScenesImportsAllRootNodes) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  json nodes = {{{"mesh", 0}, {"children", {1}}}, {{"mesh", 0}, {"translation", {0, 0, 5}}}, {{"mesh", 0}}};
  GltfImportReport report;
  auto mesh = importGltfMesh(write("noscene.gltf", b.build(triangleMesh(pos), nodes, json())), {}, &report);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(report.primitivesImported, 3u);  // roots 0 and 2, plus child 1 once
  EXPECT_EQ(mesh->indices.size(), 9u);
  expectVec3Near(mesh->positions[3], {0, 0, 5});
}

// --------------------------------------------------------------------------------------------------------
// Accessors

TEST_F(GltfImportTest, AccessorCountPastBufferIsMalformed) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  b.accessor(pos)["count"] = 4;  // the bufferView holds 3 vertices
  auto mesh = importGltfMesh(write("overrun.gltf", b.build(triangleMesh(pos), {{{"mesh", 0}}})));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
  const std::string& message = mesh.error().message;
  EXPECT_NE(message.find("overrun.gltf: mesh 0 'tri' primitive 0 accessor 0 (POSITION)"), std::string::npos)
      << message;

  // A bufferView that claims more bytes than its buffer has.
  DocBuilder c;
  const int pos2 = c.addVec3(kTriangle);
  c.view(0)["byteLength"] = 400;
  auto mesh2 = importGltfMesh(write("overrun2.gltf", c.build(triangleMesh(pos2), {{{"mesh", 0}}})));
  ASSERT_FALSE(mesh2.ok());
  EXPECT_EQ(mesh2.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(mesh2.error().message.find("bufferView 0"), std::string::npos) << mesh2.error().message;
}

TEST_F(GltfImportTest, IndexOutOfRangeIsMalformed) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  const int idx = b.addIndices16({0, 1, 3});
  auto mesh = importGltfMesh(write("badindex.gltf", b.build(triangleMesh(pos, idx), {{{"mesh", 0}}})));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(mesh.error().message.find("(indices)"), std::string::npos) << mesh.error().message;
}

TEST_F(GltfImportTest, MissingFileIsFileNotFound) {
  auto mesh = importGltfMesh((dir_ / "does_not_exist.gltf").string());
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::FileNotFound);
}

TEST_F(GltfImportTest, InvalidJsonReportsParseError) {
  auto mesh = importGltfMesh(writeText("broken.gltf", "{ \"asset\": { \"version\": \"2.0\" }, "));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(mesh.error().message.find("parse failed"), std::string::npos) << mesh.error().message;
}

TEST_F(GltfImportTest, DeeplyNestedJsonIsRejectedNotAStackOverflow) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  std::string text = b.build(triangleMesh(pos), {{{"mesh", 0}}}).dump();
  text.pop_back();  // drop the final '}' and append a pathological "extras"
  text += ",\"extras\":" + std::string(200000, '[') + std::string(200000, ']') + "}";
  auto mesh = importGltfMesh(writeText("deep.gltf", text));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(mesh.error().message.find("nesting"), std::string::npos) << mesh.error().message;
}

TEST_F(GltfImportTest, InterleavedByteStride) {
  DocBuilder b;
  // position (12 bytes) + normal (12 bytes) + uv (8 bytes) per vertex: stride 32.
  std::vector<float> interleaved = {0, 0, 0, 0, 0, 1, 0.0f, 0.0f,  //
                                    1, 0, 0, 0, 0, 1, 1.0f, 0.0f,  //
                                    0, 1, 0, 0, 0, 1, 0.0f, 1.0f};
  const int view = b.addView(interleaved, 32);
  const int pos =
      b.addAccessor({{"bufferView", view}, {"componentType", kFloat}, {"count", 3}, {"type", "VEC3"}});
  const int nrm = b.addAccessor(
      {{"bufferView", view}, {"byteOffset", 12}, {"componentType", kFloat}, {"count", 3}, {"type", "VEC3"}});
  const int uv = b.addAccessor(
      {{"bufferView", view}, {"byteOffset", 24}, {"componentType", kFloat}, {"count", 3}, {"type", "VEC2"}});
  json meshes = json::array(
      {{{"primitives", {{{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}, {"TEXCOORD_0", uv}}}}}}}});
  auto mesh = importGltfMesh(write("interleaved.gltf", b.build(meshes, {{{"mesh", 0}}})));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  ASSERT_EQ(mesh->positions.size(), 3u);
  expectVec3Near(mesh->positions[1], {1, 0, 0});
  expectVec3Near(mesh->positions[2], {0, 1, 0});
  for (const glm::vec3& n : mesh->normals) expectVec3Near(n, {0, 0, 1});
  ASSERT_EQ(mesh->uvs.size(), 3u);
  EXPECT_EQ(mesh->uvs[1], glm::vec2(1, 0));
  EXPECT_EQ(mesh->uvs[2], glm::vec2(0, 1));

  // The last element ends exactly at the end of the view; one more byte of offset runs past it.
  DocBuilder c;
  const int view2 = c.addView(interleaved, 32);
  c.addAccessor(
      {{"bufferView", view2}, {"byteOffset", 25}, {"componentType", kFloat}, {"count", 3}, {"type", "VEC2"}});
  const int pos2 =
      c.addAccessor({{"bufferView", view2}, {"componentType", kFloat}, {"count", 3}, {"type", "VEC3"}});
  json meshes2 = json::array({{{"primitives", {{{"attributes", {{"POSITION", pos2}, {"TEXCOORD_0", 0}}}}}}}});
  auto bad = importGltfMesh(write("interleaved_bad.gltf", c.build(meshes2, {{{"mesh", 0}}})));
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(bad.error().message.find("accessor 0 (TEXCOORD_0)"), std::string::npos) << bad.error().message;
}

TEST_F(GltfImportTest, SparseAccessorSubstitutesValues) {
  DocBuilder b;
  const int pos = b.addVec3({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}});
  const int idx = b.addIndices16({0, 1, 2, 2, 1, 3});
  const int sparseIndices = b.addView(std::vector<uint8_t>{1, 3});
  const int sparseValues = b.addView(std::vector<float>{5, 0, 0, 5, 5, 0});
  b.accessor(pos)["sparse"] = {{"count", 2},
                               {"indices", {{"bufferView", sparseIndices}, {"componentType", kUByte}}},
                               {"values", {{"bufferView", sparseValues}}}};
  auto mesh = importGltfMesh(write("sparse.gltf", b.build(triangleMesh(pos, idx), {{{"mesh", 0}}})));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  ASSERT_EQ(mesh->positions.size(), 4u);
  expectVec3Near(mesh->positions[0], {0, 0, 0});
  expectVec3Near(mesh->positions[1], {5, 0, 0});
  expectVec3Near(mesh->positions[2], {0, 1, 0});
  expectVec3Near(mesh->positions[3], {5, 5, 0});

  // A sparse index that is not below the accessor count is rejected.
  DocBuilder c;
  const int pos2 = c.addVec3(kTriangle);
  const int badIndices = c.addView(std::vector<uint8_t>{7});
  const int values2 = c.addView(std::vector<float>{1, 1, 1});
  c.accessor(pos2)["sparse"] = {{"count", 1},
                                {"indices", {{"bufferView", badIndices}, {"componentType", kUByte}}},
                                {"values", {{"bufferView", values2}}}};
  auto bad = importGltfMesh(write("sparse_bad.gltf", c.build(triangleMesh(pos2), {{{"mesh", 0}}})));
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::MalformedInput);
}

TEST_F(GltfImportTest, MorphTargetsUseDefaultWeightsAndSparseOnlyAccessors) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  // Target 0: a sparse accessor without a bufferView (zeros) that moves vertex 2 by (0,0,2).
  const int sparseIndices = b.addView(std::vector<uint16_t>{2});
  const int sparseValues = b.addView(std::vector<float>{0, 0, 2});
  const int delta = b.addAccessor({{"componentType", kFloat},
                                   {"count", 3},
                                   {"type", "VEC3"},
                                   {"sparse",
                                    {{"count", 1},
                                     {"indices", {{"bufferView", sparseIndices}, {"componentType", kUShort}}},
                                     {"values", {{"bufferView", sparseValues}}}}}});
  json meshes = json::array(
      {{{"weights", {0.5}},
        {"primitives", {{{"attributes", {{"POSITION", pos}}}, {"targets", {{{"POSITION", delta}}}}}}}}});
  json nodes = {{{"mesh", 0}, {"children", {1}}}, {{"mesh", 0}, {"weights", {1.0}}}};
  auto mesh = importGltfMesh(write("morph.gltf", b.build(meshes, nodes)));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  ASSERT_EQ(mesh->positions.size(), 6u);
  expectVec3Near(mesh->positions[2], {0, 1, 1});  // mesh.weights = 0.5
  expectVec3Near(mesh->positions[5], {0, 1, 2});  // node.weights = 1.0 overrides
  expectVec3Near(mesh->positions[1], {1, 0, 0});
}

TEST_F(GltfImportTest, QuantizedAttributes) {
  DocBuilder b;
  // KHR_mesh_quantization: SHORT positions (not normalized, 4-byte aligned via byteStride 8), BYTE normalized
  // normals, UNSIGNED_SHORT normalized uvs and UNSIGNED_BYTE normalized RGBA colours.
  const int posView = b.addView(std::vector<int16_t>{0, 0, 0, 0, 100, 0, 0, 0, 0, 100, 0, 0}, 8);
  const int pos =
      b.addAccessor({{"bufferView", posView}, {"componentType", kShort}, {"count", 3}, {"type", "VEC3"}});
  const int nrmView = b.addView(std::vector<int8_t>{0, 0, 127, 0, 0, 0, 127, 0, 0, 0, -128, 0}, 4);
  const int nrm = b.addAccessor({{"bufferView", nrmView},
                                 {"componentType", kByte},
                                 {"normalized", true},
                                 {"count", 3},
                                 {"type", "VEC3"}});
  const int uvView = b.addView(std::vector<uint16_t>{0, 0, 65535, 0, 0, 65535});
  const int uv = b.addAccessor({{"bufferView", uvView},
                                {"componentType", kUShort},
                                {"normalized", true},
                                {"count", 3},
                                {"type", "VEC2"}});
  const int colorView = b.addView(std::vector<uint8_t>{255, 0, 0, 128, 0, 255, 0, 255, 0, 0, 255, 0});
  const int color = b.addAccessor({{"bufferView", colorView},
                                   {"componentType", kUByte},
                                   {"normalized", true},
                                   {"count", 3},
                                   {"type", "VEC4"}});
  json meshes = json::array(
      {{{"primitives",
         {{{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}, {"TEXCOORD_0", uv}, {"COLOR_0", color}}}}}}}});
  json doc = b.build(meshes, {{{"mesh", 0}, {"scale", {0.01, 0.01, 0.01}}}});
  doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  auto mesh = importGltfMesh(write("quantized.gltf", doc));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectVec3Near(mesh->positions[1], {1, 0, 0});
  expectVec3Near(mesh->positions[2], {0, 1, 0});
  expectVec3Near(mesh->normals[0], {0, 0, 1});
  expectVec3Near(mesh->normals[2], {0, 0, -1});  // -128 clamps to -1
  EXPECT_EQ(mesh->uvs[1], glm::vec2(1, 0));
  EXPECT_EQ(mesh->colors[0], 0x800000FFu);  // R in the low byte, A = 128
  EXPECT_EQ(mesh->colors[1], 0xFF00FF00u);
  EXPECT_EQ(mesh->colors[2], 0x00FF0000u);
}

TEST_F(GltfImportTest, MissingUvsAndColorsAreFilledWithDefaults) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  const int uv = b.addFloats({0.25f, 0.5f, 0.25f, 0.5f, 0.25f, 0.5f}, "VEC2", 2);
  const int color = b.addFloats({1, 0, 0, 1, 0, 0, 1, 0, 0}, "VEC3", 3);
  json meshes = json::array({{{"primitives",
                               {{{"attributes", {{"POSITION", pos}}}},
                                {{"attributes", {{"POSITION", pos}, {"TEXCOORD_0", uv}, {"COLOR_0", color}}}},
                                {{"attributes", {{"POSITION", pos}}}}}}}});
  auto mesh = importGltfMesh(write("defaults.gltf", b.build(meshes, {{{"mesh", 0}}})));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectValidMesh(*mesh);
  ASSERT_EQ(mesh->uvs.size(), 9u);
  ASSERT_EQ(mesh->colors.size(), 9u);
  for (size_t i = 0; i < 9; ++i) {
    const bool has = i >= 3 && i < 6;
    EXPECT_EQ(mesh->uvs[i], has ? glm::vec2(0.25f, 0.5f) : glm::vec2(0, 0)) << i;
    EXPECT_EQ(mesh->colors[i], has ? 0xFF0000FFu : 0xFFFFFFFFu) << i;
  }
}

TEST_F(GltfImportTest, NormalGenerationCanBeDisabled) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  GltfImportOptions options;
  options.generateNormalsIfMissing = false;
  GltfImportReport report;
  auto mesh =
      importGltfMesh(write("nonormals.gltf", b.build(triangleMesh(pos), {{{"mesh", 0}}})), options, &report);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  ASSERT_EQ(mesh->normals.size(), 3u);
  for (const glm::vec3& n : mesh->normals) EXPECT_EQ(n, glm::vec3(0));
  EXPECT_FALSE(report.warnings.empty());
}

TEST_F(GltfImportTest, UnsupportedRequiredExtension) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  json doc = b.build(triangleMesh(pos), {{{"mesh", 0}}});
  doc["extensionsUsed"] = {"EXT_unknown_geometry_codec"};
  doc["extensionsRequired"] = {"EXT_unknown_geometry_codec"};
  auto mesh = importGltfMesh(write("unknown.gltf", doc));
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.error().code, ErrorCode::Unsupported);
}

}  // namespace
}  // namespace visbuf
