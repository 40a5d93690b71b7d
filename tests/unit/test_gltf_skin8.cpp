// Eight joint influences per vertex (glTF JOINTS_1 / WEIGHTS_1): import, renormalisation over all 8, the
// SkinVertex records of buildMesh, the CPU reference skinning (animation.h) against a sum written here from the
// file's own arrays, the pack's skin-vertex section, and the errors of malformed second sets. The file is
// tests/unit/skin8_fixture.h's; the GPU skinning pass is checked in tests/gpu/test_skin8.cpp.
#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <tuple>

#include <gtest/gtest.h>

#include "skin8_fixture.h"
#include "temp_dir_test.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/animation.h"
#include "visbuf/scene/scene.h"

namespace visbuf {
namespace {

class Skin8Test : public test::TempDirTest {
 protected:
  std::string write(const nlohmann::json& doc, const std::string& name = "skin8.gltf") {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << doc.dump();
    return path;
  }
};

// File vertex index by rest position (every grid position is distinct; buildMesh reorders vertices).
std::map<std::tuple<float, float, float>, int> vertexByPosition(const test::Skin8Fixture& f) {
  std::map<std::tuple<float, float, float>, int> out;
  for (int v = 0; v < f.vertexCount(); ++v)
    out[{f.positions[size_t(3 * v)], f.positions[size_t(3 * v + 1)], f.positions[size_t(3 * v + 2)]}] = v;
  return out;
}

// The file's weights renormalised (sum 1 over all 8), in double.
std::vector<double> normalisedWeights(const test::Skin8Fixture& f, int v) {
  std::vector<double> w(8);
  double sum = 0.0;
  for (int k = 0; k < 8; ++k) sum += (w[size_t(k)] = f.weights[size_t(8 * v + k)]);
  for (double& x : w) x /= sum;
  return w;
}

}  // namespace

// Both sets are imported in slot order, weights renormalised over all 8 (the file's sum 1.3 -> 1; 1e-6: float
// storage of the normalised weights), no warning; with a conforming file (sum 1) the same.
TEST_F(Skin8Test, ImportKeepsEightInfluencesNormalisedOverAll) {
  for (double sum : {1.0, 1.3}) {
    SCOPED_TRACE(sum);
    const test::Skin8Fixture f = test::makeSkin8Fixture(sum);
    GltfImportReport report;
    Result<ImportedScene> s = importGltfScene(write(f.doc), {}, &report);
    ASSERT_TRUE(s.ok()) << s.error().message;
    for (const std::string& w : report.warnings) ADD_FAILURE() << "unexpected warning: " << w;
    ASSERT_EQ(s->meshes.size(), 1u);
    const MeshSource& m = s->meshes[0].source;
    ASSERT_EQ(m.joints.size(), size_t(f.vertexCount()));
    ASSERT_EQ(m.joints1.size(), m.joints.size());
    ASSERT_EQ(m.weights1.size(), m.joints.size());
    for (int v = 0; v < f.vertexCount(); ++v) {
      const std::vector<double> w = normalisedWeights(f, v);
      double total = 0.0;
      for (int k = 0; k < 8; ++k) {
        const float got = k < 4 ? m.weights[size_t(v)][k] : m.weights1[size_t(v)][k - 4];
        const uint16_t joint = k < 4 ? m.joints[size_t(v)][k] : m.joints1[size_t(v)][k - 4];
        EXPECT_NEAR(got, w[size_t(k)], 1e-6) << "vertex " << v << " slot " << k;
        EXPECT_EQ(joint, f.joints[size_t(8 * v + k)]) << "vertex " << v << " slot " << k;
        total += got;
      }
      EXPECT_NEAR(total, 1.0, 1e-6);
      double second = 0.0;
      for (int k = 4; k < 8; ++k) second += w[size_t(k)];
      EXPECT_GT(second, 0.3) << "set 1 must carry a real share of every vertex";
    }
  }
}

// buildMesh's SkinVertex records hold the 8 influences of the file vertex at the same rest position, and the CPU
// reference skinning (skinPosition / skinNormal, animation.h) equals the blend written here from the file's raw
// arrays: p' = sum_k w_k J_{j_k} p, n' = cofactor(sum_k w_k J_{j_k}) n normalised, with J = joint matrices of
// the clip at t = 0.6. Bound 1e-6 (float weights, double arithmetic). The blend of only the first 4 influences
// lands at least 0.05 away, so the check would see a dropped second set.
TEST_F(Skin8Test, SkinVerticesAndCpuSkinningUseAllEight) {
  const test::Skin8Fixture f = test::makeSkin8Fixture();
  Result<ImportedScene> imported = importGltfScene(write(f.doc));
  ASSERT_TRUE(imported.ok()) << imported.error().message;
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  ASSERT_EQ(scene->skinnedObjects.size(), 1u);
  const SkinnedObject& so = scene->skinnedObjects[0];
  const Mesh& mesh = scene->meshes[scene->objects[so.object].mesh];
  ASSERT_EQ(mesh.skinVertices.size(), mesh.vertices.size());
  const auto byPosition = vertexByPosition(f);
  const std::vector<glm::dmat4> joints = skinnedObjectJoints(*scene, so, 0.6);
  ASSERT_EQ(joints.size(), 8u);
  double maxPosition = 0.0, maxNormal = 0.0, minTruncated = INFINITY;
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const gpu::Vertex& rest = mesh.vertices[v];
    auto it = byPosition.find({rest.px, rest.py, rest.pz});
    ASSERT_NE(it, byPosition.end()) << "vertex " << v << " is not a file vertex";
    const int fv = it->second;
    const std::vector<double> w = normalisedWeights(f, fv);
    const SkinVertex& sv = mesh.skinVertices[v];
    glm::dmat4 blend(0.0), firstFour(0.0);
    double firstFourSum = 0.0;
    for (int k = 0; k < 8; ++k) {
      EXPECT_EQ(sv.joints[k], f.joints[size_t(8 * fv + k)]) << "vertex " << v << " slot " << k;
      EXPECT_NEAR(sv.weights[k], w[size_t(k)], 1e-6) << "vertex " << v << " slot " << k;
      const glm::dmat4& j = joints[f.joints[size_t(8 * fv + k)]];
      blend += j * w[size_t(k)];
      if (k < 4) firstFour += j * w[size_t(k)], firstFourSum += w[size_t(k)];
    }
    const glm::dvec3 p(rest.px, rest.py, rest.pz);
    const glm::dvec3 want(blend * glm::dvec4(p, 1.0));
    maxPosition = std::max(maxPosition, glm::length(skinPosition(p, sv, joints) - want));
    const glm::dmat3 b(blend);
    const glm::dmat3 cofactor(glm::cross(b[1], b[2]), glm::cross(b[2], b[0]), glm::cross(b[0], b[1]));
    const glm::dvec3 wantNormal = glm::normalize(cofactor * glm::dvec3(0.0, 0.0, 1.0));  // det > 0 here
    maxNormal = std::max(maxNormal, glm::length(skinNormal(glm::dvec3(0.0, 0.0, 1.0), sv, joints) - wantNormal));
    minTruncated = std::min(minTruncated,
                            glm::length(glm::dvec3(firstFour * glm::dvec4(p, 1.0)) / firstFourSum - want));
  }
  std::printf("8-influence CPU skinning vs the file's blend: position %.2e, normal %.2e; first-4-only blend off by "
              ">= %.3f\n",
              maxPosition, maxNormal, minTruncated);
  EXPECT_LE(maxPosition, 1e-6);
  EXPECT_LE(maxNormal, 1e-6);
  EXPECT_GE(minTruncated, 0.05);
}

// The pack's "skinVertices" section carries all 8 slots: a written and re-read scene has the same records, byte
// for byte.
TEST_F(Skin8Test, PackKeepsEightInfluences) {
  const test::Skin8Fixture f = test::makeSkin8Fixture();
  Result<ImportedScene> imported = importGltfScene(write(f.doc));
  ASSERT_TRUE(imported.ok()) << imported.error().message;
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  Result<std::vector<uint8_t>> bytes = serializePack(*scene);
  ASSERT_TRUE(bytes.ok()) << bytes.error().message;
  Result<Scene> back = parsePack(bytes->data(), bytes->size(), "skin8.vbp");
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->meshes.size(), scene->meshes.size());
  size_t eight = 0;
  for (size_t m = 0; m < scene->meshes.size(); ++m) {
    const std::vector<SkinVertex>& a = scene->meshes[m].skinVertices;
    const std::vector<SkinVertex>& b = back->meshes[m].skinVertices;
    ASSERT_EQ(a.size(), b.size());
    if (a.empty()) continue;
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(SkinVertex)), 0);
    for (const SkinVertex& s : b) eight += s.weights[7] > 0.0f;
  }
  EXPECT_EQ(eight, size_t(f.vertexCount()));
}

// Malformed second sets: JOINTS_1 without WEIGHTS_1 (and the reverse) and a JOINTS_1 index beyond the skin's
// joints are refused with messages naming the primitive and the attribute; a third set warns (ignored, the 8
// are renormalised without it).
TEST_F(Skin8Test, MalformedSecondSetIsRefused) {
  const test::Skin8Fixture f = test::makeSkin8Fixture();
  auto attributes = [](nlohmann::json& doc) -> nlohmann::json& {
    return doc["meshes"][0]["primitives"][0]["attributes"];
  };
  for (const char* drop : {"WEIGHTS_1", "JOINTS_1"}) {
    nlohmann::json doc = f.doc;
    attributes(doc).erase(drop);
    Result<ImportedScene> s = importGltfScene(write(doc));
    ASSERT_FALSE(s.ok()) << drop;
    EXPECT_EQ(s.error().code, ErrorCode::MalformedInput);
    EXPECT_NE(s.error().message.find("mesh 0 'strip8' primitive 0: JOINTS_1 and WEIGHTS_1 must come together"),
              std::string::npos)
        << s.error().message;
  }
  {
    nlohmann::json doc = f.doc;
    doc["skins"][0]["joints"] = {1, 2, 3, 4, 5};  // joints 5..7 of JOINTS_1 now out of range
    doc["skins"][0].erase("inverseBindMatrices");
    Result<ImportedScene> s = importGltfScene(write(doc));
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.error().message.find("not below the skin's joint count 5 (JOINTS_1)"), std::string::npos)
        << s.error().message;
  }
  {
    nlohmann::json doc = f.doc;
    attributes(doc)["JOINTS_2"] = attributes(doc)["JOINTS_1"];
    attributes(doc)["WEIGHTS_2"] = attributes(doc)["WEIGHTS_1"];
    GltfImportReport report;
    Result<ImportedScene> s = importGltfScene(write(doc), {}, &report);
    ASSERT_TRUE(s.ok()) << s.error().message;
    bool warned = false;
    for (const std::string& w : report.warnings) warned = warned || w.find("JOINTS_2+") != std::string::npos;
    EXPECT_TRUE(warned);
  }
}

}  // namespace visbuf
