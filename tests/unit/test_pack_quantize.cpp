// Quantised packs (error bounds, and the reported error against an independent recomputation) and the encoded
// geometry streams (decoded with meshoptimizer's own API against the scene).
#include "pack_test_util.h"

namespace visbuf {
namespace {

using namespace pack_test;

TEST(PackQuantize, RoundTripWithinHalfAStep) {
  const Scene scene = makeQuantizeTestScene();
  PackWriteReport report;
  Result<std::vector<uint8_t>> bytes = serializePack(scene, PackWriteOptions{true}, &report);
  ASSERT_TRUE(bytes) << bytes.error().message;
  ASSERT_TRUE(report.quantization.enabled);
  EXPECT_FALSE(hasSection(*bytes, "vertices"));
  uint64_t vertexCount = 0;
  for (const Mesh& m : scene.meshes) vertexCount += m.vertices.size();
  const pack::SectionEntry qv = entryOf(*bytes, sectionIndex(*bytes, "qvertices"));
  EXPECT_EQ(qv.elementSize, 1u);  // encoded bytes
  EXPECT_EQ(entryOf(*bytes, sectionIndex(*bytes, "quantization")).count, scene.meshes.size());
  EXPECT_EQ(report.quantization.vertices, vertexCount);
  EXPECT_EQ(report.quantization.bytesSaved, int64_t(12 * vertexCount) - int64_t(40 * scene.meshes.size()));

  Result<Scene> back = parse(*bytes);
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->meshes.size(), scene.meshes.size());
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    SCOPED_TRACE("mesh " + std::to_string(i));
    const Mesh& x = scene.meshes[i];
    const Mesh& y = back->meshes[i];
    const pack::QuantizationRecord q = quantizationOf(*bytes, i);
    ASSERT_EQ(x.vertices.size(), y.vertices.size());
    EXPECT_EQ(x.indices, y.indices);
    EXPECT_EQ(x.tangents, y.tangents);
    EXPECT_EQ(x.uvs1, y.uvs1);
    ASSERT_EQ(x.skinVertices.size(), y.skinVertices.size());
    EXPECT_TRUE(x.skinVertices.empty() ||  // memcmp with the null data() of empty vectors is undefined
                std::memcmp(x.skinVertices.data(), y.skinVertices.data(),
                            x.skinVertices.size() * sizeof(SkinVertex)) == 0);
    ASSERT_EQ(x.lods.size(), y.lods.size());
    for (size_t l = 0; l < x.lods.size(); ++l) {
      EXPECT_EQ(x.lods[l].firstIndex, y.lods[l].firstIndex);
      EXPECT_EQ(x.lods[l].indexCount, y.lods[l].indexCount);
      EXPECT_GE(y.lods[l].error, x.lods[l].error + report.quantization.meshMaxPositionError[i]);
    }
    EXPECT_EQ(y.boundsSphere.x, x.boundsSphere.x);  // the centre stays, the radius may grow
    EXPECT_GE(y.boundsSphere.w, x.boundsSphere.w);
    // Half a step per axis, plus float rounding of the decode (a few ulps of the largest magnitude involved).
    auto bound = [](float offset, float scale) {
      return double(scale) / 65535.0 / 2.0 + 4.0 * DBL_EPSILON + 2.0 * FLT_EPSILON * (std::abs(offset) + scale);
    };
    const double centreX = y.boundsSphere.x, centreY = y.boundsSphere.y, centreZ = y.boundsSphere.z;
    for (size_t v = 0; v < x.vertices.size(); ++v) {
      const gpu::Vertex& a = x.vertices[v];
      const gpu::Vertex& b = y.vertices[v];
      const float pa[] = {a.px, a.py, a.pz}, pb[] = {b.px, b.py, b.pz};
      for (int c = 0; c < 3; ++c) {
        if (std::abs(double(pa[c]) - double(pb[c])) > bound(q.positionOffset[c], q.positionScale[c])) {
          ADD_FAILURE() << "vertex " << v << " axis " << c << ": " << pa[c] << " -> " << pb[c];
        }
      }
      if (std::abs(double(a.u) - double(b.u)) > bound(q.uvOffset[0], q.uvScale[0]) ||
          std::abs(double(a.v) - double(b.v)) > bound(q.uvOffset[1], q.uvScale[1])) {
        ADD_FAILURE() << "vertex " << v << " uv: " << a.u << "," << a.v << " -> " << b.u << "," << b.v;
      }
      if (a.normal != b.normal || a.color != b.color) {
        ADD_FAILURE() << "vertex " << v << ": normal or colour changed";
      }
      const double d = std::sqrt((b.px - centreX) * (b.px - centreX) + (b.py - centreY) * (b.py - centreY) +
                                 (b.pz - centreZ) * (b.pz - centreZ));
      if (d > double(y.boundsSphere.w)) {
        ADD_FAILURE() << "vertex " << v << " is " << d << " from the centre, outside radius " << y.boundsSphere.w;
      }
    }
  }
  // Everything but the vertices, bounds and LOD errors is exactly the plain round trip.
  Scene rest = *back;
  rest.meshes = scene.meshes;
  expectScenesEqual(scene, rest);
  // The saving is measured on the decoded records: 12 bytes a vertex less the quantisation records.
  EXPECT_EQ(report.quantization.bytesSaved,
            int64_t(12 * vertexCount) - int64_t(entryOf(*bytes, sectionIndex(*bytes, "quantization")).size));
}

TEST(PackQuantize, ReportedErrorsMatchAnIndependentRecomputation) {
  const Scene scene = makeQuantizeTestScene();
  PackWriteReport report;
  Result<std::vector<uint8_t>> bytes = serializePack(scene, PackWriteOptions{true}, &report);
  ASSERT_TRUE(bytes);
  Result<Scene> back = parse(*bytes);
  ASSERT_TRUE(back) << back.error().message;
  // Recompute from what the reader decodes, in double: Euclidean distances per vertex.
  double maxError = 0, sumSq = 0, maxRel = 0, sumSqRel = 0, maxUv = 0, maxNormal = 0;
  size_t n = 0;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const Mesh& x = scene.meshes[i];
    const Mesh& y = back->meshes[i];
    double meshMax = 0;
    for (size_t v = 0; v < x.vertices.size(); ++v) {
      const gpu::Vertex& a = x.vertices[v];
      const gpu::Vertex& b = y.vertices[v];
      const double dx = double(a.px) - b.px, dy = double(a.py) - b.py, dz = double(a.pz) - b.pz;
      const double e = std::sqrt(dx * dx + dy * dy + dz * dz);
      const double rel = e / double(x.boundsSphere.w);
      meshMax = std::max(meshMax, e);
      maxRel = std::max(maxRel, rel);
      sumSq += e * e;
      sumSqRel += rel * rel;
      maxUv = std::max(maxUv, std::hypot(double(a.u) - b.u, double(a.v) - b.v));
      const glm::vec3 na = octDecode(a.normal), nb = octDecode(b.normal);
      maxNormal = std::max(maxNormal, double(glm::length(na - nb)));
      ++n;
    }
    maxError = std::max(maxError, meshMax);
    EXPECT_NEAR(report.quantization.meshMaxPositionError[i], meshMax, 1e-7 * meshMax + 1e-12);
    for (size_t l = 0; l < x.lods.size(); ++l) {
      EXPECT_GE(double(y.lods[l].error), double(x.lods[l].error) + meshMax) << "mesh " << i << " LOD " << l;
    }
  }
  const PackQuantizationReport& q = report.quantization;
  EXPECT_GT(maxError, 0.0);
  EXPECT_NEAR(q.maxPositionError, maxError, 1e-12 * maxError);
  EXPECT_NEAR(q.rmsPositionError, std::sqrt(sumSq / double(n)), 1e-9 * maxError);
  EXPECT_NEAR(q.maxRelativePositionError, maxRel, 1e-12 * maxRel);
  EXPECT_NEAR(q.rmsRelativePositionError, std::sqrt(sumSqRel / double(n)), 1e-9 * maxRel);
  EXPECT_NEAR(q.maxUvError, maxUv, 1e-12 * maxUv);
  EXPECT_EQ(q.maxNormalError, 0.0);
  EXPECT_EQ(maxNormal, 0.0);
  // And the magnitudes are what 16 bits give: the knot spans a few units, so errors are ~1e-5.
  EXPECT_LT(q.maxRelativePositionError, 2e-5);
}

// Decodes with meshoptimizer's own API (not pack_geometry.h) and compares with the scene the pack was written from:
// every mesh's streams lie back to back in mesh order and decode to its data bit for bit.
TEST(PackGeometry, EncodedSectionsDecodeToTheSceneExactly) {
  const Scene scene = makeTexturedTestScene();
  Result<std::vector<uint8_t>> bytes = serializePack(scene);
  ASSERT_TRUE(bytes) << bytes.error().message;
  const pack::SectionEntry vertices = entryOf(*bytes, sectionIndex(*bytes, "vertices"));
  const pack::SectionEntry indices = entryOf(*bytes, sectionIndex(*bytes, "indices"));
  const pack::SectionEntry streams = entryOf(*bytes, sectionIndex(*bytes, "meshStreams"));
  const pack::SectionEntry tangents = entryOf(*bytes, sectionIndex(*bytes, "tangents"));
  const pack::SectionEntry uvs1 = entryOf(*bytes, sectionIndex(*bytes, "uvs1"));
  EXPECT_EQ(entryOf(*bytes, sectionIndex(*bytes, "meshEncoding")).count, scene.meshes.size());
  uint64_t vertexCursor = 0, indexCursor = 0, rawBytes = 0;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    SCOPED_TRACE("mesh " + std::to_string(i));
    const Mesh& m = scene.meshes[i];
    const pack::MeshEncodingRecord e = encodingOf(*bytes, i);
    EXPECT_EQ(e.vertexCount, m.vertices.size());
    EXPECT_EQ(e.indexCount, m.indices.size());
    EXPECT_EQ(e.reserved, 0u);
    EXPECT_EQ(e.vertexByte, vertexCursor);
    EXPECT_EQ(e.indexByte, indexCursor);
    vertexCursor += e.vertexBytes;
    indexCursor += e.indexBytes;
    std::vector<gpu::Vertex> v(m.vertices.size());
    ASSERT_EQ(meshopt_decodeVertexBuffer(v.data(), v.size(), sizeof(gpu::Vertex),
                                         bytes->data() + vertices.offset + e.vertexByte, e.vertexBytes), 0);
    EXPECT_EQ(std::memcmp(v.data(), m.vertices.data(), v.size() * sizeof(gpu::Vertex)), 0);
    std::vector<uint32_t> idx(m.indices.size());
    const uint8_t* at = bytes->data() + indices.offset + e.indexByte;
    ASSERT_EQ(e.indexCodec == pack::kIndexCodecTriangles
                  ? meshopt_decodeIndexBuffer(idx.data(), idx.size(), 4, at, e.indexBytes)
                  : meshopt_decodeIndexSequence(idx.data(), idx.size(), 4, at, e.indexBytes),
              0);
    EXPECT_EQ(idx, m.indices);
    pack::MeshStreamsRecord r;
    std::memcpy(&r, bytes->data() + streams.offset + i * sizeof(r), sizeof(r));
    EXPECT_EQ(r.tangentByte == pack::kNoStream, m.tangents.empty());
    if (!m.tangents.empty()) {
      std::vector<glm::vec4> t(m.vertices.size());
      ASSERT_EQ(meshopt_decodeVertexBuffer(t.data(), t.size(), 16, bytes->data() + tangents.offset + r.tangentByte,
                                           r.tangentBytes), 0);
      EXPECT_EQ(t, m.tangents);
    }
    if (!m.uvs1.empty()) {
      std::vector<glm::vec2> u(m.vertices.size());
      ASSERT_EQ(meshopt_decodeVertexBuffer(u.data(), u.size(), 8, bytes->data() + uvs1.offset + r.uv1Byte, r.uv1Bytes),
                0);
      EXPECT_EQ(u, m.uvs1);
    }
    rawBytes += m.vertices.size() * sizeof(gpu::Vertex) + m.indices.size() * sizeof(uint32_t);
  }
  EXPECT_EQ(vertexCursor, vertices.size);
  EXPECT_EQ(indexCursor, indices.size);
  EXPECT_LT(vertices.size + indices.size, rawBytes);  // it does compress
  // The same scene always gives the same bytes (pinned codec versions, no state between calls).
  Result<std::vector<uint8_t>> again = serializePack(scene);
  ASSERT_TRUE(again);
  EXPECT_TRUE(*again == *bytes);
}

// A baked asset's meshes have their triangles in the order the triangle codec reproduces (buildImportedScene), so
// every mesh uses it and the round trip is exact; an arbitrary rotation falls back to the exact sequence codec.
TEST(PackGeometry, BakedMeshesUseTheTriangleCodec) {
  for (const char* asset : {"Fox/glTF/Fox.gltf", "CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb"}) {
    SCOPED_TRACE(asset);
    Result<ImportedScene> imported = importGltfScene(assetPath(asset));
    ASSERT_TRUE(imported) << imported.error().message;
    Result<Scene> scene = buildImportedScene(*imported);
    ASSERT_TRUE(scene) << scene.error().message;
    Result<std::vector<uint8_t>> bytes = serializePack(*scene);
    ASSERT_TRUE(bytes);
    for (size_t i = 0; i < scene->meshes.size(); ++i)
      EXPECT_EQ(encodingOf(*bytes, i).indexCodec, pack::kIndexCodecTriangles) << "mesh " << i;
    Result<Scene> back = parse(*bytes);
    ASSERT_TRUE(back) << back.error().message;
    for (size_t i = 0; i < scene->meshes.size(); ++i) EXPECT_EQ(back->meshes[i].indices, scene->meshes[i].indices);
  }
  // Rotating one triangle of a codec-ordered mesh: the triangle codec would undo the rotation, so the writer keeps
  // the exact order with the sequence codec.
  Scene scene = makeTestScene(16, 6);
  std::vector<uint32_t>& idx = scene.meshes[0].indices;
  ASSERT_TRUE(pack::rotateTrianglesToCodecOrder(idx));
  Result<std::vector<uint8_t>> canonical = serializePack(scene);
  ASSERT_TRUE(canonical);
  EXPECT_EQ(encodingOf(*canonical, 0).indexCodec, pack::kIndexCodecTriangles);
  std::rotate(idx.begin() + 3, idx.begin() + 4, idx.begin() + 6);
  Result<std::vector<uint8_t>> rotated = serializePack(scene);
  ASSERT_TRUE(rotated);
  EXPECT_EQ(encodingOf(*rotated, 0).indexCodec, pack::kIndexCodecSequence);
  Result<Scene> back = parse(*rotated);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->meshes[0].indices, idx);
}

}  // namespace
}  // namespace visbuf
