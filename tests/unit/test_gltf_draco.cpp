// KHR_draco_mesh_compression: Draco twins of the repository's assets, made when the test runs with Debian's
// draco_transcoder (at stated quantisation bits), imported and compared with the uncompressed original on the
// CPU: the same triangles (Draco reorders vertices and triangles), each corner's position, normal, texture
// coordinates, colour and skin within the quantisation bound. A morph twin is made with libdraco's encoder
// (draco_transcoder refuses morph targets), its uncompressed targets written in the decoded point order as
// the extension's implementation note asks of generators. Hostile streams: tests/hostile_cases/draco.py.
#include <gtest/gtest.h>

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "temp_dir_test.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Quantisation bits of the twins (draco_transcoder -qp -qt -qn -qc -qw): positions, texture coordinates,
// normals, colours and weights.
constexpr int kPositionBits = 16;
constexpr int kTexCoordBits = 14;
constexpr int kNormalBits = 12;
constexpr int kColorBits = 10;
constexpr int kWeightBits = 12;
constexpr const char* kDracoExtName = "KHR_draco_mesh_compression";

#ifndef VISBUF_DRACO_TRANSCODER
#error "tests/CMakeLists.txt defines VISBUF_DRACO_TRANSCODER (the path of draco_transcoder, or empty)"
#endif

class GltfDraco : public test::TempDirTest {
 protected:
  // The Draco twin of `asset` (relative to an asset folder), written by draco_transcoder into the temp dir.
  fs::path transcode(const std::string& asset) {
    const fs::path in = test::assetPath(asset);
    const fs::path out = dir_ / (in.stem().string() + ".draco.glb");
    const std::string command = std::string(VISBUF_DRACO_TRANSCODER) + " -i '" + in.string() + "' -o '" +
                                out.string() + "' -qp " + std::to_string(kPositionBits) + " -qt " +
                                std::to_string(kTexCoordBits) + " -qn " + std::to_string(kNormalBits) + " -qc " +
                                std::to_string(kColorBits) + " -qw " + std::to_string(kWeightBits) + " > /dev/null";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    return out;
  }
};

// The largest extent of the mesh's positions (the range Draco quantises is at most this per primitive).
float extentOf(const MeshSource& m) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : m.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::vec3 e = hi - lo;
  return std::max({e.x, e.y, e.z, 1e-30f});
}

struct Tolerance {
  float position, normal, uv, weight;
  bool normals = true;  // false: the file has no normals (they are generated from the triangles, and Draco's
                        // transcoder welds the vertices that the original kept apart, so they differ)
};

// Whether corner `a` of `x` and corner `b` of `y` hold the same vertex within `tol`.
bool sameCorner(const MeshSource& x, uint32_t a, const MeshSource& y, uint32_t b, const Tolerance& tol) {
  if (glm::length(x.positions[a] - y.positions[b]) > tol.position) return false;
  if (tol.normals && glm::length(x.normals[a] - y.normals[b]) > tol.normal) return false;
  if (!x.uvs.empty() && glm::length(x.uvs[a] - y.uvs[b]) > tol.uv) return false;
  if (!x.colors.empty()) {
    for (int c = 0; c < 4; ++c) {
      const int u = int((x.colors[a] >> (8 * c)) & 0xFF), v = int((y.colors[b] >> (8 * c)) & 0xFF);
      if (std::abs(u - v) > 1) return false;
    }
  }
  if (!x.joints.empty()) {
    // Slots are compared by joint: a zero-weight slot's joint is 0 on both sides (MeshSource's contract).
    for (int k = 0; k < 4; ++k) {
      if (x.joints[a][k] != y.joints[b][k] && x.weights[a][k] > tol.weight) return false;
      if (std::abs(x.weights[a][k] - y.weights[b][k]) > tol.weight) return false;
    }
  }
  return true;
}

// Every triangle of `twin` is a triangle of `original` (same corners within `tol`, same winding, any rotation),
// one to one. Brute force over centroids: the meshes here have at most a few thousand triangles.
void expectSameTriangles(const MeshSource& original, const MeshSource& twin, const Tolerance& tol,
                         const std::string& what) {
  ASSERT_EQ(original.indices.size(), twin.indices.size()) << what;
  ASSERT_EQ(original.uvs.empty(), twin.uvs.empty()) << what;
  ASSERT_EQ(original.colors.empty(), twin.colors.empty()) << what;
  ASSERT_EQ(original.joints.empty(), twin.joints.empty()) << what;
  const size_t n = original.indices.size() / 3;
  auto centroid = [](const MeshSource& m, size_t t) {
    return (m.positions[m.indices[3 * t]] + m.positions[m.indices[3 * t + 1]] + m.positions[m.indices[3 * t + 2]]) /
           3.0f;
  };
  std::vector<glm::vec3> centroids(n);
  for (size_t t = 0; t < n; ++t) centroids[t] = centroid(original, t);
  std::vector<uint8_t> used(n, 0);
  size_t unmatched = 0;
  for (size_t t = 0; t < n; ++t) {
    const glm::vec3 c = centroid(twin, t);
    bool found = false;
    for (size_t o = 0; o < n && !found; ++o) {
      if (used[o] || glm::length(centroids[o] - c) > tol.position) continue;
      for (int r = 0; r < 3 && !found; ++r) {
        bool all = true;
        for (int k = 0; k < 3 && all; ++k)
          all = sameCorner(original, original.indices[3 * o + size_t((k + r) % 3)], twin, twin.indices[3 * t + size_t(k)], tol);
        if (all) used[o] = 1, found = true;
      }
    }
    if (!found && ++unmatched <= 3) ADD_FAILURE() << what << ": twin triangle " << t << " matches no original triangle";
  }
  EXPECT_EQ(unmatched, 0u) << what;
}

// Imports both files as scenes and compares them mesh by mesh (draco_transcoder keeps meshes, materials, nodes,
// skins and animations in order; only the primitives' data is re-encoded).
void expectTwinMatches(const fs::path& original, const fs::path& twin, bool normals) {
  auto a = importGltfScene(original.string());
  ASSERT_TRUE(a.ok()) << a.error().message;
  GltfImportReport report;
  auto b = importGltfScene(twin.string(), {}, &report);
  ASSERT_TRUE(b.ok()) << b.error().message;
  ASSERT_EQ(a->meshes.size(), b->meshes.size());
  ASSERT_EQ(a->instances.size(), b->instances.size());
  ASSERT_EQ(a->skins.size(), b->skins.size());
  ASSERT_EQ(a->animations.size(), b->animations.size());
  for (size_t m = 0; m < a->meshes.size(); ++m) {
    const MeshSource& x = a->meshes[m].source;
    const MeshSource& y = b->meshes[m].source;
    const float extent = extentOf(x);
    // Per axis a quantised coordinate is off by at most half a step of the primitive's range (<= the mesh's
    // extent); a vector by sqrt(3) of that; doubled for the float round trip.
    const Tolerance tol{extent * std::ldexp(1.0f, -kPositionBits) * 2.0f,
                        // Octahedral normals: a step of 2 / 2^bits on each of two coordinates.
                        4.0f * std::ldexp(1.0f, -(kNormalBits - 1)),
                        4.0f * std::ldexp(1.0f, -kTexCoordBits) * 16.0f,  // texture coordinates span up to 16
                        // Weights: quantised then renormalised by the import (4 slots).
                        4.0f * std::ldexp(1.0f, -kWeightBits), normals};
    expectSameTriangles(x, y, tol, "mesh " + std::to_string(m) + " '" + x.name + "'");
  }
}

TEST_F(GltfDraco, TranscodedTwinsImportLikeTheirOriginals) {
  if (std::string(VISBUF_DRACO_TRANSCODER).empty()) GTEST_SKIP() << "draco_transcoder was not found at configure time";
  // (Fox has no normals: the import generates them, from welded vertices in the twin.)
  for (const auto& [asset, normals] : {std::pair{"BoxInterleaved/glTF/BoxInterleaved.gltf", true},
                                       std::pair{"Fox/glTF-Binary/Fox.glb", false},
                                       std::pair{"CesiumMan/glTF/CesiumMan.gltf", true},
                                       std::pair{"CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb", true},
                                       std::pair{"MultiUVTest/glTF/MultiUVTest.gltf", true},
                                       std::pair{"RiggedSimple/glTF/RiggedSimple.gltf", true}}) {
    SCOPED_TRACE(asset);
    REQUIRE_ASSET(test::assetPath(asset).string());
    expectTwinMatches(test::assetPath(asset), transcode(asset), normals);
  }
}

// The sample repository's own Draco file (Box/glTF-Draco, made by the glTF-Pipeline) against Box/glTF.
TEST_F(GltfDraco, SampleBoxMatchesItsUncompressedTwin) {
  const auto draco = test::extraAsset("Box/glTF-Draco/Box.gltf");
  const auto plain = test::extraAsset("Box/glTF/Box.gltf");
  if (!draco || !plain) GTEST_SKIP() << "Box/glTF-Draco is in the extra corpus (VISBUF_EXTRA_ASSETS) only";
  expectTwinMatches(*plain, *draco, true);
}


// Reads a whole file.
std::vector<uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Float accessor `a` of `doc` (tightly packed in its bufferView of buffer 0), as n-vectors.
std::vector<float> floatsOf(const json& doc, const std::vector<uint8_t>& bin, int a) {
  const json& acc = doc["accessors"][size_t(a)];
  const json& view = doc["bufferViews"][acc["bufferView"].get<size_t>()];
  const size_t n = acc["type"] == "VEC4" ? 4 : 3;
  std::vector<float> out(acc["count"].get<size_t>() * n);
  std::memcpy(out.data(), bin.data() + view.value("byteOffset", size_t{0}) + acc.value("byteOffset", size_t{0}),
              out.size() * sizeof(float));
  return out;
}

// AnimatedMorphCube as a Draco-compressed primitive (POSITION, NORMAL, TANGENT in the stream, edgebreaker, which
// reorders points) beside its two uncompressed morph targets, written in the decoded point order; both files
// get the morph weights (0.5, 0.7) so that importGltfMesh bakes the morphed shape. The baked triangles and the
// scene import's kept targets must match the original's.
TEST_F(GltfDraco, MorphTargetsBesideACompressedPrimitive) {
  const fs::path src = test::assetPath("AnimatedMorphCube/glTF/AnimatedMorphCube.gltf");
  REQUIRE_ASSET(src.string());
  json doc = json::parse(readBytes(src));
  const std::vector<uint8_t> bin = readBytes(src.parent_path() / doc["buffers"][0]["uri"].get<std::string>());
  json& prim = doc["meshes"][0]["primitives"][0];
  const int posA = prim["attributes"]["POSITION"], nrmA = prim["attributes"]["NORMAL"], tanA = prim["attributes"]["TANGENT"];
  const std::vector<float> pos = floatsOf(doc, bin, posA), nrm = floatsOf(doc, bin, nrmA), tan = floatsOf(doc, bin, tanA);
  const size_t points = pos.size() / 3;
  const json& idxAcc = doc["accessors"][prim["indices"].get<size_t>()];
  const json& idxView = doc["bufferViews"][idxAcc["bufferView"].get<size_t>()];
  std::vector<uint16_t> indices(idxAcc["count"].get<size_t>());
  std::memcpy(indices.data(), bin.data() + idxView.value("byteOffset", size_t{0}), indices.size() * 2);

  // The Draco mesh and its stream.
  draco::Mesh mesh;
  mesh.set_num_points(static_cast<uint32_t>(points));
  auto addAttribute = [&](draco::GeometryAttribute::Type type, const std::vector<float>& values, int n) {
    draco::GeometryAttribute ga;
    ga.Init(type, nullptr, static_cast<uint8_t>(n), draco::DT_FLOAT32, false, int64_t(sizeof(float)) * n, 0);
    const int id = mesh.AddAttribute(ga, true, static_cast<uint32_t>(points));
    for (size_t i = 0; i < points; ++i)
      mesh.attribute(id)->SetAttributeValue(draco::AttributeValueIndex(static_cast<uint32_t>(i)), &values[i * size_t(n)]);
    return static_cast<int>(mesh.attribute(id)->unique_id());
  };
  const int posId = addAttribute(draco::GeometryAttribute::POSITION, pos, 3);
  const int nrmId = addAttribute(draco::GeometryAttribute::NORMAL, nrm, 3);
  const int tanId = addAttribute(draco::GeometryAttribute::GENERIC, tan, 4);
  for (size_t f = 0; f < indices.size() / 3; ++f)
    mesh.AddFace({draco::PointIndex(indices[3 * f]), draco::PointIndex(indices[3 * f + 1]), draco::PointIndex(indices[3 * f + 2])});
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, kPositionBits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, kNormalBits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::GENERIC, kNormalBits);
  encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
  draco::EncoderBuffer stream;
  ASSERT_TRUE(encoder.EncodeMeshToBuffer(mesh, &stream).ok());

  // The decoded point order: each decoded point is the original vertex of the same position and normal.
  draco::DecoderBuffer in;
  in.Init(stream.data(), stream.size());
  auto decoded = draco::Decoder().DecodeMeshFromBuffer(&in);
  ASSERT_TRUE(decoded.ok());
  const draco::Mesh& d = *decoded.value();
  ASSERT_EQ(d.num_points(), points);
  std::vector<size_t> original(points);
  for (uint32_t p = 0; p < points; ++p) {
    float dp[3], dn[3];
    ASSERT_TRUE(d.GetAttributeByUniqueId(uint32_t(posId))->ConvertValue<float>(d.GetAttributeByUniqueId(uint32_t(posId))->mapped_index(draco::PointIndex(p)), 3, dp));
    ASSERT_TRUE(d.GetAttributeByUniqueId(uint32_t(nrmId))->ConvertValue<float>(d.GetAttributeByUniqueId(uint32_t(nrmId))->mapped_index(draco::PointIndex(p)), 3, dn));
    float best = INFINITY;
    for (size_t v = 0; v < points; ++v) {
      const float e = glm::length(glm::vec3(dp[0], dp[1], dp[2]) - glm::vec3(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2])) * 100.0f +
                      glm::length(glm::vec3(dn[0], dn[1], dn[2]) - glm::vec3(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2]));
      if (e < best) best = e, original[p] = v;
    }
  }
  bool reordered = false;
  for (size_t p = 0; p < points; ++p) reordered = reordered || original[p] != p;
  EXPECT_TRUE(reordered) << "the edgebreaker stream kept the point order: the test would not see a wrong order";

  // The twin: the stream appended to the buffer, the primitive's accessors data-less, the targets reordered in
  // place (their bufferViews are tightly packed VEC3 floats).
  std::vector<uint8_t> twinBin = bin;
  for (const json& target : prim["targets"]) {
    for (const auto& [semantic, accessor] : target.items()) {
      const json& acc = doc["accessors"][accessor.get<size_t>()];
      const size_t offset = doc["bufferViews"][acc["bufferView"].get<size_t>()].value("byteOffset", size_t{0});
      for (size_t p = 0; p < points; ++p)
        std::memcpy(twinBin.data() + offset + p * 12, bin.data() + offset + original[p] * 12, 12);
    }
  }
  json twin = doc;
  json& tprim = twin["meshes"][0]["primitives"][0];
  while (twinBin.size() % 4 != 0) twinBin.push_back(0);
  twin["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", twinBin.size()}, {"byteLength", stream.size()}});
  twinBin.insert(twinBin.end(), stream.data(), stream.data() + stream.size());
  twin["buffers"][0] = {{"uri", "twin.bin"}, {"byteLength", twinBin.size()}};
  for (int a : {posA, nrmA, tanA, tprim["indices"].get<int>()}) {
    twin["accessors"][size_t(a)].erase("bufferView");
    twin["accessors"][size_t(a)].erase("byteOffset");
  }
  tprim["extensions"][kDracoExtName] = {{"bufferView", twin["bufferViews"].size() - 1},
                                        {"attributes", {{"POSITION", posId}, {"NORMAL", nrmId}, {"TANGENT", tanId}}}};
  twin["extensionsUsed"] = {kDracoExtName};
  twin["extensionsRequired"] = {kDracoExtName};
  doc["meshes"][0]["weights"] = twin["meshes"][0]["weights"] = {0.5, 0.7};
  doc["buffers"][0]["uri"] = "original.bin";
  {
    std::ofstream(dir_ / "twin.bin", std::ios::binary).write(reinterpret_cast<const char*>(twinBin.data()), std::streamsize(twinBin.size()));
    std::ofstream(dir_ / "original.bin", std::ios::binary).write(reinterpret_cast<const char*>(bin.data()), std::streamsize(bin.size()));
    std::ofstream(dir_ / "twin.gltf") << twin.dump();
    std::ofstream(dir_ / "original.gltf") << doc.dump();
  }

  // Baked at weights (0.5, 0.7): the same morphed triangles.
  auto a = importGltfMesh((dir_ / "original.gltf").string());
  ASSERT_TRUE(a.ok()) << a.error().message;
  auto b = importGltfMesh((dir_ / "twin.gltf").string());
  ASSERT_TRUE(b.ok()) << b.error().message;
  const Tolerance tol{extentOf(*a) * std::ldexp(1.0f, -kPositionBits) * 2.0f, 4.0f * std::ldexp(1.0f, -(kNormalBits - 1)),
                      0.0f, 0.0f, true};
  expectSameTriangles(*a, *b, tol, "morphed AnimatedMorphCube");
  // The scene import keeps the targets (the weights are animated): each twin vertex's deltas are its original
  // vertex's, exactly (targets are not compressed).
  auto sa = importGltfScene((dir_ / "original.gltf").string());
  auto sb = importGltfScene((dir_ / "twin.gltf").string());
  ASSERT_TRUE(sa.ok() && sb.ok());
  ASSERT_EQ(sa->meshes.size(), 1u);
  ASSERT_EQ(sb->meshes.size(), 1u);
  const MeshSource& x = sa->meshes[0].source;
  const MeshSource& y = sb->meshes[0].source;
  ASSERT_EQ(x.morphTargets.size(), 2u);
  ASSERT_EQ(y.morphTargets.size(), 2u);
  for (size_t v = 0; v < y.positions.size(); ++v) {
    size_t match = x.positions.size();
    for (size_t u = 0; u < x.positions.size() && match == x.positions.size(); ++u)
      if (glm::length(x.positions[u] - y.positions[v]) <= tol.position && glm::length(x.normals[u] - y.normals[v]) <= tol.normal)
        match = u;
    ASSERT_LT(match, x.positions.size()) << "twin vertex " << v;
    for (size_t t = 0; t < 2; ++t) {
      EXPECT_EQ(x.morphTargets[t].positions[match], y.morphTargets[t].positions[v]) << "vertex " << v << " target " << t;
      EXPECT_EQ(x.morphTargets[t].normals[match], y.morphTargets[t].normals[v]) << "vertex " << v << " target " << t;
    }
  }
}


// A primitive with both a Draco stream and uncompressed accessors (bufferViews), the extension only used: a stream
// that cannot be decoded leaves the uncompressed data, with a warning naming the stream; the same file requiring
// the extension is refused, naming it.
TEST_F(GltfDraco, UncompressedFallbackWhenTheStreamCannotBeDecoded) {
  const fs::path src = test::assetPath("BoxInterleaved/glTF/BoxInterleaved.gltf");
  REQUIRE_ASSET(src.string());
  json doc = json::parse(readBytes(src));
  std::vector<uint8_t> bin = readBytes(src.parent_path() / doc["buffers"][0]["uri"].get<std::string>());
  const size_t garbage = bin.size();
  for (int i = 0; i < 64; ++i) bin.push_back(static_cast<uint8_t>(i * 37 + 11));
  doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", garbage}, {"byteLength", 64}});
  doc["buffers"][0] = {{"uri", "box.bin"}, {"byteLength", bin.size()}};
  json& prim = doc["meshes"][0]["primitives"][0];
  prim["extensions"][kDracoExtName] = {{"bufferView", doc["bufferViews"].size() - 1},
                                       {"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}};
  doc["extensionsUsed"] = {kDracoExtName};
  std::ofstream(dir_ / "box.bin", std::ios::binary).write(reinterpret_cast<const char*>(bin.data()), std::streamsize(bin.size()));
  std::ofstream(dir_ / "used.gltf") << doc.dump();
  doc["extensionsRequired"] = {kDracoExtName};
  std::ofstream(dir_ / "required.gltf") << doc.dump();

  auto original = importGltfMesh(src.string());
  ASSERT_TRUE(original.ok()) << original.error().message;
  GltfImportReport report;
  auto used = importGltfMesh((dir_ / "used.gltf").string(), {}, &report);
  ASSERT_TRUE(used.ok()) << used.error().message;
  EXPECT_EQ(used->positions, original->positions);
  EXPECT_EQ(used->indices, original->indices);
  bool warned = false;
  for (const std::string& w : report.warnings)
    warned = warned || (w.find("Draco stream") != std::string::npos && w.find("uncompressed data") != std::string::npos);
  EXPECT_TRUE(warned) << "no warning names the stream and the fallback";
  auto required = importGltfMesh((dir_ / "required.gltf").string());
  ASSERT_FALSE(required.ok());
  EXPECT_EQ(required.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(required.error().message.find("Draco stream"), std::string::npos) << required.error().message;
}

}  // namespace
}  // namespace visbuf
