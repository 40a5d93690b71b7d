// Tests for importGltfMesh's containers (engine/asset/gltf_container.cpp): a binary .glb and buffers compressed with
// EXT_meshopt_compression, built here from the same documents as test_gltf_import.cpp.
#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <cstdint>
#include <string>
#include <vector>

#include "gltf_doc_builder.h"
#include "mesh_source_checks.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf {
namespace {

using nlohmann::json;
using test::base64;
using test::DocBuilder;
using test::GltfImportTest;
using test::kFloat;
using test::kTriangle;
using test::kUShort;
using test::makeGlb;
using test::triangleMesh;

// --------------------------------------------------------------------------------------------------------
// Containers and compression

TEST_F(GltfImportTest, GlbContainer) {
  DocBuilder b;
  const int pos = b.addVec3(kTriangle);
  json doc = b.build(triangleMesh(pos), {{{"mesh", 0}}});
  doc["buffers"][0].erase("uri");  // GLB: buffer 0 is the BIN chunk
  const std::vector<uint8_t> glb = makeGlb(doc.dump(), b.bytes());
  auto mesh = importGltfMesh(writeBytes("tri.glb", glb));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->indices.size(), 3u);

  // Same bytes under a .gltf name: the magic decides.
  auto renamed = importGltfMesh(writeBytes("tri_glb.gltf", glb));
  ASSERT_TRUE(renamed.ok()) << renamed.error().message;

  // Truncated file: the BIN chunk runs past the end.
  std::vector<uint8_t> truncated(glb.begin(), glb.end() - 8);
  const uint32_t length = static_cast<uint32_t>(truncated.size());
  std::memcpy(truncated.data() + 8, &length, 4);
  auto cut = importGltfMesh(writeBytes("cut.glb", truncated));
  ASSERT_FALSE(cut.ok());
  EXPECT_EQ(cut.error().code, ErrorCode::MalformedInput);

  // .glb without the magic.
  auto notGlb = importGltfMesh(writeText("text.glb", doc.dump()));
  ASSERT_FALSE(notGlb.ok());
  EXPECT_EQ(notGlb.error().code, ErrorCode::MalformedInput);
}

// Builds a document whose positions and indices live only in EXT_meshopt_compression streams (encoded here
// with meshoptimizer), with the uncompressed bufferViews in a fallback buffer that has no uri.
json meshoptDoc(const std::vector<glm::vec3>& positions, const std::vector<uint16_t>& indices,
                std::vector<uint8_t>* compressed) {
  std::vector<uint8_t> vertexStream(meshopt_encodeVertexBufferBound(positions.size(), sizeof(glm::vec3)));
  vertexStream.resize(meshopt_encodeVertexBuffer(vertexStream.data(), vertexStream.size(), positions.data(),
                                                 positions.size(), sizeof(glm::vec3)));
  std::vector<uint8_t> indexStream(meshopt_encodeIndexBufferBound(indices.size(), positions.size()));
  indexStream.resize(
      meshopt_encodeIndexBuffer(indexStream.data(), indexStream.size(), indices.data(), indices.size()));
  *compressed = vertexStream;
  while (compressed->size() % 4 != 0) compressed->push_back(0);
  const size_t indexOffset = compressed->size();
  compressed->insert(compressed->end(), indexStream.begin(), indexStream.end());

  const size_t vertexBytes = positions.size() * 12;
  const size_t indexBytes = indices.size() * 2;
  json ext = {{"EXT_meshopt_compression", json::object()}};
  return {{"asset", {{"version", "2.0"}}},
          {"extensionsUsed", {"EXT_meshopt_compression"}},
          {"extensionsRequired", {"EXT_meshopt_compression"}},
          {"buffers",
           {{{"byteLength", compressed->size()},
             {"uri", "data:application/octet-stream;base64," + base64(*compressed)}},
            {{"byteLength", vertexBytes + indexBytes},
             {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}}}},
          {"bufferViews",
           {{{"buffer", 1},
             {"byteLength", vertexBytes},
             {"byteStride", 12},
             {"extensions",
              {{"EXT_meshopt_compression",
                {{"buffer", 0},
                 {"byteLength", vertexStream.size()},
                 {"byteStride", 12},
                 {"count", positions.size()},
                 {"mode", "ATTRIBUTES"}}}}}},
            {{"buffer", 1},
             {"byteOffset", vertexBytes},
             {"byteLength", indexBytes},
             {"extensions",
              {{"EXT_meshopt_compression",
                {{"buffer", 0},
                 {"byteOffset", indexOffset},
                 {"byteLength", indexStream.size()},
                 {"byteStride", 2},
                 {"count", indices.size()},
                 {"mode", "TRIANGLES"}}}}}}}},
          {"accessors",
           {{{"bufferView", 0}, {"componentType", kFloat}, {"count", positions.size()}, {"type", "VEC3"}},
            {{"bufferView", 1}, {"componentType", kUShort}, {"count", indices.size()}, {"type", "SCALAR"}}}},
          {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
          {"nodes", {{{"mesh", 0}}}},
          {"scenes", {{{"nodes", {0}}}}},
          {"scene", 0}};
}

TEST_F(GltfImportTest, MeshoptCompressedBufferViews) {
  const std::vector<glm::vec3> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 0.5f}};
  const std::vector<uint16_t> indices = {0, 1, 2, 2, 1, 3, 3, 1, 4};
  std::vector<uint8_t> compressed;
  json doc = meshoptDoc(positions, indices, &compressed);
  auto mesh = importGltfMesh(write("meshopt.gltf", doc));
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  ASSERT_EQ(mesh->positions.size(), positions.size());
  for (size_t i = 0; i < positions.size(); ++i) EXPECT_EQ(mesh->positions[i], positions[i]) << i;
  EXPECT_EQ(mesh->indices, (std::vector<uint32_t>(indices.begin(), indices.end())));

  // Corrupt stream (truncated) -> MalformedInput, not a crash.
  json corrupt = doc;
  corrupt["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["byteLength"] = 3;
  auto bad = importGltfMesh(write("meshopt_corrupt.gltf", corrupt));
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::MalformedInput);

  // A filter this importer does not know, with the extension required and no fallback data -> Unsupported.
  json unknown = doc;
  unknown["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["filter"] = "FUTURE";
  auto unsupported = importGltfMesh(write("meshopt_future.gltf", unknown));
  ASSERT_FALSE(unsupported.ok());
  EXPECT_EQ(unsupported.error().code, ErrorCode::Unsupported);
}

}  // namespace
}  // namespace visbuf
