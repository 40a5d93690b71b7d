// glTF import of the third-party sample assets in the repository's assets/ (test_assets.h): each skips when the
// file is missing. The import's own cases, on tiny generated documents: test_gltf_import.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "mesh_source_checks.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;
using test::expectValidMesh;
using test::expectVec3Near;
using test::geometricNormal;

#define REQUIRE_SHARED_ASSET(var, relative)                              \
  const std::optional<std::string> var = test::assetPath(relative).string(); \
  REQUIRE_ASSET(*var)

// Every triangle's counter-clockwise normal agrees with its vertices' stored normals (flat-shaded boxes).
void expectFlatNormalsMatchWinding(const MeshSource& m) {
  for (size_t t = 0; t < m.indices.size() / 3; ++t) {
    const glm::vec3 g = geometricNormal(m, t);
    for (int k = 0; k < 3; ++k)
      EXPECT_GT(glm::dot(g, m.normals[m.indices[3 * t + k]]), 0.99f) << "triangle " << t;
  }
}

TEST(GltfImportAssets, Kitten) {
  REQUIRE_SHARED_ASSET(path, "Kitten/kitten.glb");
  GltfImportReport report;
  auto mesh = importGltfMesh(*path, {}, &report);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectValidMesh(*mesh);
  EXPECT_EQ(mesh->indices.size() / 3, 28944u);
  EXPECT_EQ(mesh->positions.size(), 14856u);
  EXPECT_TRUE(mesh->uvs.empty());
  EXPECT_EQ(report.primitivesImported, 1u);
}

TEST(GltfImportAssets, BoxMeshopt) {
  for (const char* file : {"BoxMeshopt/BoxMeshopt.gltf", "BoxMeshopt/BoxMeshopt.glb"}) {
    SCOPED_TRACE(file);
    REQUIRE_SHARED_ASSET(path, file);
    auto mesh = importGltfMesh(*path);
    ASSERT_TRUE(mesh.ok()) << mesh.error().message;
    expectValidMesh(*mesh);
    EXPECT_EQ(mesh->indices.size() / 3, 12u);
    EXPECT_EQ(mesh->positions.size(), 24u);
    for (const glm::vec3& p : mesh->positions) {  // the unit cube: quantized +-1 scaled by 0.5
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(std::abs(p[c]), 0.5f, 1e-4f);
    }
    expectFlatNormalsMatchWinding(*mesh);
  }
}

TEST(GltfImportAssets, BoxInterleaved) {
  REQUIRE_SHARED_ASSET(path, "BoxInterleaved/glTF/BoxInterleaved.gltf");
  auto mesh = importGltfMesh(*path);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectValidMesh(*mesh);
  EXPECT_EQ(mesh->indices.size() / 3, 12u);
  expectFlatNormalsMatchWinding(*mesh);
}

TEST(GltfImportAssets, TriangleWithoutIndices) {
  REQUIRE_SHARED_ASSET(path, "TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf");
  auto mesh = importGltfMesh(*path);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectValidMesh(*mesh);
  EXPECT_EQ(mesh->indices, (std::vector<uint32_t>{0, 1, 2}));
}

TEST(GltfImportAssets, SimpleSparseAccessor) {
  REQUIRE_SHARED_ASSET(path, "SimpleSparseAccessor/glTF/SimpleSparseAccessor.gltf");
  auto mesh = importGltfMesh(*path);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  expectValidMesh(*mesh);
  EXPECT_EQ(mesh->indices.size() / 3, 12u);
  ASSERT_EQ(mesh->positions.size(), 14u);
  // The sparse part lifts vertices 8, 10 and 12 (y = 1 in the dense data).
  expectVec3Near(mesh->positions[8], {1, 2, 0});
  expectVec3Near(mesh->positions[10], {3, 3, 0});
  expectVec3Near(mesh->positions[12], {5, 4, 0});
  expectVec3Near(mesh->positions[9], {2, 1, 0});
}

TEST(GltfImportAssets, MeshPrimitiveModes) {
  // 00-03 and 07-10 are points/lines only; the rest are two triangles each as list, strip or fan.
  for (int i = 0; i < 16; ++i) {
    char name[96];
    std::snprintf(name, sizeof(name), "Mesh_PrimitiveMode/Mesh_PrimitiveMode/Mesh_PrimitiveMode_%02d.gltf",
                  i);
    SCOPED_TRACE(name);
    REQUIRE_SHARED_ASSET(path, std::string(name));
    GltfImportReport report;
    auto mesh = importGltfMesh(*path, {}, &report);
    const bool hasTriangles = (i >= 4 && i <= 6) || i >= 11;
    if (hasTriangles) {
      ASSERT_TRUE(mesh.ok()) << mesh.error().message;
      expectValidMesh(*mesh);
      EXPECT_EQ(mesh->indices.size() / 3, 2u);
    } else {
      ASSERT_FALSE(mesh.ok());
      EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
      EXPECT_NE(mesh.error().message.find("no triangle geometry"), std::string::npos);
      EXPECT_EQ(report.primitivesSkipped, 1u);
    }
  }
}

TEST(GltfImportAssets, EveryAssetImportsOrFailsCleanly) {
  REQUIRE_SHARED_ASSET(root, "");
  int imported = 0;
  for (const auto& entry : fs::recursive_directory_iterator(*root)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".gltf" && ext != ".glb") continue;
    SCOPED_TRACE(entry.path().string());
    auto mesh = importGltfMesh(entry.path().string());
    const std::string file = entry.path().filename().string();
    if (file == "BoxWithInfinites.glb") {  // infinite vertex data on purpose
      ASSERT_FALSE(mesh.ok());
      EXPECT_EQ(mesh.error().code, ErrorCode::MalformedInput);
    } else if (file.rfind("Mesh_PrimitiveMode_", 0) == 0 && !mesh.ok()) {
      EXPECT_NE(mesh.error().message.find("no triangle geometry"), std::string::npos);
    } else {
      ASSERT_TRUE(mesh.ok()) << mesh.error().message;
      expectValidMesh(*mesh);
      ++imported;
    }
  }
  EXPECT_GT(imported, 0);
}

}  // namespace
}  // namespace visbuf
