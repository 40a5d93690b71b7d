// Hand-made EXT_mesh_gpu_instancing files for the importer's unit tests and the GPU render test: one mesh (an
// octahedron, 8 triangles with normals) drawn by one node (itself under a translated, rotated, scaled parent)
// with N instances, gltfpack-style (TRANSLATION and SCALE as FLOAT, ROTATION as normalized SHORT), and the
// equivalent expanded file: the same parent with one child node per instance whose TRS is the instance's,
// written as the values the instanced file decodes to (normalized shorts -> max(c / 32767, -1), then float, as
// glTF readers keep accessor data). Both describe the same world transforms.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_assets.h"

namespace visbuf::test {

struct InstancingOptions {
  uint32_t instances = 4096;
  bool translation = true, rotation = true, scale = true;
  int rotationComponentType = 5122;  // SHORT (normalized); 5120 BYTE (normalized); 5126 FLOAT
  bool required = false;              // list the extension in extensionsRequired too
};

struct InstancingFiles {
  nlohmann::json instanced;
  nlohmann::json expanded;
};

inline InstancingFiles makeInstancingFiles(const InstancingOptions& o = {}) {
  const float pos[] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
  const uint16_t idx[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  std::vector<float> t, s;
  std::vector<int16_t> r16;
  std::vector<int8_t> r8;
  std::vector<float> rf;
  nlohmann::json children = nlohmann::json::array(), expandedNodes = nlohmann::json::array();
  const uint32_t side = uint32_t(std::ceil(std::cbrt(double(o.instances))));
  for (uint32_t i = 0; i < o.instances; ++i) {
    const float tx = float(i % side) * 3.0f, ty = float((i / side) % side) * 3.0f, tz = float(i / side / side) * 3.0f;
    t.insert(t.end(), {tx, ty, tz});
    const float sc[3] = {0.5f + float(i % 7) * 0.125f, 0.75f + float(i % 5) * 0.1f, 0.6f + float(i % 3) * 0.2f};
    s.insert(s.end(), sc, sc + 3);
    // A unit quaternion per instance, about a varying axis; stored quantised, decoded as glTF says.
    const double angle = 0.37 * i, ax = std::sin(0.11 * i), ay = std::cos(0.07 * i), az = 0.4;
    const double len = std::sqrt(ax * ax + ay * ay + az * az), sn = std::sin(angle / 2);
    const double q[4] = {ax / len * sn, ay / len * sn, az / len * sn, std::cos(angle / 2)};
    double decoded[4];
    for (int c = 0; c < 4; ++c) {
      if (o.rotationComponentType == 5122) {
        const int16_t v = int16_t(std::lround(q[c] * 32767.0));
        r16.push_back(v);
        decoded[c] = double(float(std::max(v / 32767.0, -1.0)));
      } else if (o.rotationComponentType == 5120) {
        const int8_t v = int8_t(std::lround(q[c] * 127.0));
        r8.push_back(v);
        decoded[c] = double(float(std::max(v / 127.0, -1.0)));
      } else {
        rf.push_back(float(q[c]));
        decoded[c] = double(float(q[c]));
      }
    }
    nlohmann::json node = {{"mesh", 0}};
    if (o.translation) node["translation"] = {double(tx), double(ty), double(tz)};
    if (o.rotation) node["rotation"] = {decoded[0], decoded[1], decoded[2], decoded[3]};
    if (o.scale) node["scale"] = {double(sc[0]), double(sc[1]), double(sc[2])};
    expandedNodes.push_back(node);
    children.push_back(i + 1);
  }

  std::vector<uint8_t> bin;
  nlohmann::json views = nlohmann::json::array(), accessors = nlohmann::json::array();
  auto add = [&](const void* data, size_t bytes, int componentType, const char* type, size_t count, bool normalized) {
    while (bin.size() % 4 != 0) bin.push_back(0);
    const size_t offset = bin.size();
    bin.resize(offset + bytes);
    std::memcpy(bin.data() + offset, data, bytes);
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}});
    nlohmann::json a = {{"bufferView", views.size() - 1}, {"componentType", componentType}, {"count", count},
                        {"type", type}};
    if (normalized) a["normalized"] = true;
    accessors.push_back(a);
    return int(accessors.size() - 1);
  };
  const int position = add(pos, sizeof pos, 5126, "VEC3", 6, false);
  accessors[size_t(position)]["min"] = {-1, -1, -1};
  accessors[size_t(position)]["max"] = {1, 1, 1};
  const int normal = add(pos, sizeof pos, 5126, "VEC3", 6, false);  // an octahedron's vertex normals
  const int index = add(idx, sizeof idx, 5123, "SCALAR", 24, false);
  // The shared part: buffer (before the instance data), mesh, the parent node with its transform.
  const size_t sharedBytes = bin.size();
  nlohmann::json attributes = nlohmann::json::object();
  if (o.translation) attributes["TRANSLATION"] = add(t.data(), t.size() * 4, 5126, "VEC3", o.instances, false);
  if (o.rotation) {
    if (o.rotationComponentType == 5122)
      attributes["ROTATION"] = add(r16.data(), r16.size() * 2, 5122, "VEC4", o.instances, true);
    else if (o.rotationComponentType == 5120)
      attributes["ROTATION"] = add(r8.data(), r8.size(), 5120, "VEC4", o.instances, true);
    else
      attributes["ROTATION"] = add(rf.data(), rf.size() * 4, 5126, "VEC4", o.instances, false);
  }
  if (o.scale) attributes["SCALE"] = add(s.data(), s.size() * 4, 5126, "VEC3", o.instances, false);

  const double h = std::sin(0.25), c = std::cos(0.25);  // parent: 0.5 rad about +Y
  const nlohmann::json parent = {{"name", "parent"},
                                 {"translation", {10.0, -2.0, 4.0}},
                                 {"rotation", {0.0, h, 0.0, c}},
                                 {"scale", {1.5, 1.5, 1.5}}};
  const nlohmann::json mesh = {
      {"name", "octahedron"},
      {"primitives", {{{"attributes", {{"POSITION", position}, {"NORMAL", normal}}}, {"indices", index}}}}};
  auto document = [&](const std::vector<uint8_t>& bytes, const nlohmann::json& views_, const nlohmann::json& accessors_,
                      const nlohmann::json& nodes) {
    return nlohmann::json{
        {"asset", {{"version", "2.0"}, {"generator", "visbuf tests (gltfpack-style instancing)"}}},
        {"buffers", {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + base64(bytes)}}}},
        {"bufferViews", views_},
        {"accessors", accessors_},
        {"meshes", {mesh}},
        {"nodes", nodes},
        {"scenes", {{{"nodes", {0}}}}},
        {"scene", 0}};
  };
  InstancingFiles out;
  nlohmann::json instancedParent = parent;
  instancedParent["children"] = {1};
  nlohmann::json instancedNode = {{"name", "instanced"},
                                  {"mesh", 0},
                                  {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", attributes}}}}}};
  out.instanced = document(bin, views, accessors, nlohmann::json::array({instancedParent, instancedNode}));
  out.instanced["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  if (o.required) out.instanced["extensionsRequired"] = {"EXT_mesh_gpu_instancing"};
  nlohmann::json expandedParent = parent;
  expandedParent["children"] = children;
  nlohmann::json nodes = nlohmann::json::array({expandedParent});
  for (auto& n : expandedNodes) nodes.push_back(n);
  std::vector<uint8_t> shared(bin.begin(), bin.begin() + std::ptrdiff_t(sharedBytes));
  out.expanded = document(shared, nlohmann::json(views.begin(), views.begin() + 3),
                          nlohmann::json(accessors.begin(), accessors.begin() + 3), nodes);
  return out;
}

}  // namespace visbuf::test
