// A hand-made skinned glTF whose every vertex has 8 joint influences (JOINTS_0 / WEIGHTS_0 and JOINTS_1 /
// WEIGHTS_1), for the importer's unit tests and the skinning pass's GPU test. The raw arrays written into the
// file are kept beside it, so that tests compute their expectations from the file's own numbers (independent
// of the importer's conversion into SkinVertex records).
//
// Geometry: a 9 x 3 grid of vertices in the z = 0 plane (x in [0, 8], y in [0, 2]), normals +Z, 32 triangles.
// Skeleton: node 0 (root, children 1..8), joints = nodes 1..8 at x = 0..7 (joint k at (k, 0, 0)), inverse bind
// matrices the inverse of those translations; node 9 draws the mesh with skin 0. Clip 0 rotates every joint
// from identity (t = 0) to a joint-specific rotation (t = 1), LINEAR, so every influence moves differently.
// Influences: vertex v uses all 8 joints in a vertex-specific order, with weights that are not uniform and put
// about half of the total on set 1, so dropping JOINTS_1 / WEIGHTS_1 would move every vertex visibly.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_assets.h"

namespace visbuf::test {

struct Skin8Fixture {
  nlohmann::json doc;
  std::vector<float> positions;   // 3 per vertex
  std::vector<uint16_t> joints;   // 8 per vertex: JOINTS_0's 4, then JOINTS_1's
  std::vector<float> weights;     // 8 per vertex, as written (their sum: `weightSum`)
  static constexpr int kColumns = 9, kRows = 3, kJoints = 8;
  static int vertexCount() { return kColumns * kRows; }
};

// `weightSum`: what each vertex's 8 weights add up to in the file (1 for a conforming file; other values test the
// importer's renormalisation over all 8).
inline Skin8Fixture makeSkin8Fixture(double weightSum = 1.0) {
  Skin8Fixture f;
  const int n = Skin8Fixture::vertexCount();
  std::vector<float> normals;
  for (int r = 0; r < Skin8Fixture::kRows; ++r)
    for (int c = 0; c < Skin8Fixture::kColumns; ++c) {
      f.positions.insert(f.positions.end(), {float(c), float(r), 0.0f});
      normals.insert(normals.end(), {0.0f, 0.0f, 1.0f});
    }
  std::vector<uint16_t> indices;
  for (int r = 0; r + 1 < Skin8Fixture::kRows; ++r)
    for (int c = 0; c + 1 < Skin8Fixture::kColumns; ++c) {
      const uint16_t a = uint16_t(r * Skin8Fixture::kColumns + c), b = uint16_t(a + 1),
                     d = uint16_t(a + Skin8Fixture::kColumns), e = uint16_t(d + 1);
      indices.insert(indices.end(), {a, b, e, a, e, d});
    }
  for (int v = 0; v < n; ++v) {
    // Joint order: a rotation of 0..7 by v, reversed on odd vertices; raw weights 1..8 permuted, so every slot
    // (set 0 and set 1) carries a different share at different vertices.
    double raw[8], total = 0.0;
    for (int k = 0; k < 8; ++k) {
      const int j = (v % 2 == 0) ? (k + v) % 8 : (7 - k + v) % 8;
      f.joints.push_back(uint16_t(j));
      raw[k] = 1.0 + double((k * 5 + v * 3) % 8);
      total += raw[k];
    }
    for (int k = 0; k < 8; ++k) f.weights.push_back(float(raw[k] / total * weightSum));
  }
  std::vector<float> inverseBinds;
  for (int k = 0; k < Skin8Fixture::kJoints; ++k) {
    const float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -float(k), 0, 0, 1};
    inverseBinds.insert(inverseBinds.end(), m, m + 16);
  }
  std::vector<float> times = {0.0f, 1.0f};
  std::vector<float> rotations;  // per joint: identity, then a turn of 0.25 + 0.1 k rad about a joint-specific axis
  for (int k = 0; k < Skin8Fixture::kJoints; ++k) {
    const double angle = 0.25 + 0.1 * k;
    double ax = std::cos(0.7 * k), ay = std::sin(0.7 * k), az = 0.5;
    const double len = std::sqrt(ax * ax + ay * ay + az * az);
    ax /= len, ay /= len, az /= len;
    const double s = std::sin(angle / 2);
    rotations.insert(rotations.end(), {0.0f, 0.0f, 0.0f, 1.0f, float(ax * s), float(ay * s), float(az * s),
                                       float(std::cos(angle / 2))});
  }

  // One buffer: every array appended, 4-byte aligned, one bufferView each.
  std::vector<uint8_t> bin;
  nlohmann::json views = nlohmann::json::array(), accessors = nlohmann::json::array();
  auto add = [&](const void* data, size_t bytes, int componentType, const char* type, size_t count) {
    while (bin.size() % 4 != 0) bin.push_back(0);
    const size_t offset = bin.size();
    bin.resize(offset + bytes);
    std::memcpy(bin.data() + offset, data, bytes);
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}});
    accessors.push_back({{"bufferView", views.size() - 1}, {"componentType", componentType}, {"count", count},
                         {"type", type}});
    return int(accessors.size() - 1);
  };
  constexpr int kFloat = 5126, kUShort = 5123;
  std::vector<uint16_t> joints0, joints1;
  std::vector<float> weights0, weights1;
  for (int v = 0; v < n; ++v)
    for (int k = 0; k < 8; ++k) {
      (k < 4 ? joints0 : joints1).push_back(f.joints[size_t(v * 8 + k)]);
      (k < 4 ? weights0 : weights1).push_back(f.weights[size_t(v * 8 + k)]);
    }
  const int pos = add(f.positions.data(), f.positions.size() * 4, kFloat, "VEC3", size_t(n));
  accessors[size_t(pos)]["min"] = {0.0, 0.0, 0.0};
  accessors[size_t(pos)]["max"] = {8.0, 2.0, 0.0};
  const int nrm = add(normals.data(), normals.size() * 4, kFloat, "VEC3", size_t(n));
  const int j0 = add(joints0.data(), joints0.size() * 2, kUShort, "VEC4", size_t(n));
  const int j1 = add(joints1.data(), joints1.size() * 2, kUShort, "VEC4", size_t(n));
  const int w0 = add(weights0.data(), weights0.size() * 4, kFloat, "VEC4", size_t(n));
  const int w1 = add(weights1.data(), weights1.size() * 4, kFloat, "VEC4", size_t(n));
  const int idx = add(indices.data(), indices.size() * 2, kUShort, "SCALAR", indices.size());
  const int ibm = add(inverseBinds.data(), inverseBinds.size() * 4, kFloat, "MAT4", size_t(Skin8Fixture::kJoints));
  const int keys = add(times.data(), times.size() * 4, kFloat, "SCALAR", times.size());
  accessors[size_t(keys)]["min"] = {0.0};
  accessors[size_t(keys)]["max"] = {1.0};
  nlohmann::json samplers = nlohmann::json::array(), channels = nlohmann::json::array();
  nlohmann::json nodes = nlohmann::json::array();
  nodes.push_back({{"name", "root"}, {"children", {1, 2, 3, 4, 5, 6, 7, 8}}});
  for (int k = 0; k < Skin8Fixture::kJoints; ++k) {
    nodes.push_back({{"name", "joint" + std::to_string(k)}, {"translation", {double(k), 0.0, 0.0}}});
    const int out = add(&rotations[size_t(k) * 8], 8 * 4, kFloat, "VEC4", 2);
    samplers.push_back({{"input", keys}, {"output", out}, {"interpolation", "LINEAR"}});
    channels.push_back({{"sampler", k}, {"target", {{"node", k + 1}, {"path", "rotation"}}}});
  }
  nodes.push_back({{"name", "skinned"}, {"mesh", 0}, {"skin", 0}});
  f.doc = {{"asset", {{"version", "2.0"}}},
           {"buffers", {{{"byteLength", bin.size()},
                         {"uri", "data:application/octet-stream;base64," + base64(bin)}}}},
           {"bufferViews", views},
           {"accessors", accessors},
           {"meshes",
            {{{"name", "strip8"},
              {"primitives",
               {{{"attributes",
                  {{"POSITION", pos}, {"NORMAL", nrm}, {"JOINTS_0", j0}, {"WEIGHTS_0", w0}, {"JOINTS_1", j1},
                   {"WEIGHTS_1", w1}}},
                 {"indices", idx}}}}}}},
           {"nodes", nodes},
           {"skins", {{{"joints", {1, 2, 3, 4, 5, 6, 7, 8}}, {"inverseBindMatrices", ibm}, {"skeleton", 0}}}},
           {"animations", {{{"name", "bend"}, {"samplers", samplers}, {"channels", channels}}}},
           {"scenes", {{{"nodes", {0, 9}}}}},
           {"scene", 0}};
  return f;
}

}  // namespace visbuf::test
