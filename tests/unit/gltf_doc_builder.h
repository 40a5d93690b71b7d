// The fixture of the glTF import tests (test_gltf_import.cpp, test_gltf_container.cpp): a tiny .gltf document
// built in memory -- JSON with nlohmann::json and one buffer embedded as a base64 data URI, so every byte of the
// input is visible in the test -- written into a temporary folder.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "temp_dir_test.h"
#include "test_assets.h"  // (test::base64)

namespace visbuf::test {

using nlohmann::json;

inline constexpr int kByte = 5120;
inline constexpr int kUByte = 5121;
inline constexpr int kShort = 5122;
inline constexpr int kUShort = 5123;
inline constexpr int kFloat = 5126;

// Builds a glTF document around one binary buffer: each add*() call appends raw data (4-byte aligned), a
// bufferView over it and an accessor, and returns the accessor index.
class DocBuilder {
 public:
  // Appends raw bytes and a bufferView over them; returns the bufferView index.
  template <typename T>
  int addView(const std::vector<T>& values, std::optional<int> byteStride = std::nullopt) {
    while (bytes_.size() % 4 != 0) bytes_.push_back(0);
    const size_t offset = bytes_.size();
    bytes_.resize(offset + values.size() * sizeof(T));
    if (!values.empty()) std::memcpy(bytes_.data() + offset, values.data(), values.size() * sizeof(T));
    json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * sizeof(T)}};
    if (byteStride) view["byteStride"] = *byteStride;
    views_.push_back(view);
    return static_cast<int>(views_.size()) - 1;
  }

  int addAccessor(json accessor) {
    accessors_.push_back(std::move(accessor));
    return static_cast<int>(accessors_.size()) - 1;
  }

  int addFloats(const std::vector<float>& values, const char* type, int components) {
    const int view = addView(values);
    return addAccessor({{"bufferView", view},
                        {"componentType", kFloat},
                        {"count", values.size() / static_cast<size_t>(components)},
                        {"type", type}});
  }
  int addVec3(const std::vector<glm::vec3>& v) {
    std::vector<float> flat;
    for (const glm::vec3& p : v) flat.insert(flat.end(), {p.x, p.y, p.z});
    return addFloats(flat, "VEC3", 3);
  }
  int addIndices16(const std::vector<uint16_t>& indices) {
    const int view = addView(indices);
    return addAccessor(
        {{"bufferView", view}, {"componentType", kUShort}, {"count", indices.size()}, {"type", "SCALAR"}});
  }

  json& accessor(int index) { return accessors_[static_cast<size_t>(index)]; }
  json& view(int index) { return views_[static_cast<size_t>(index)]; }
  std::vector<uint8_t>& bytes() { return bytes_; }

  // The complete document with the buffer embedded as a data URI. `meshes` / `nodes` / `scenes` as glTF JSON.
  json build(json meshes, json nodes, json scenes = json::array({{{"nodes", {0}}}})) const {
    json doc = {{"asset", {{"version", "2.0"}}},
                {"buffers",
                 {{{"byteLength", bytes_.size()},
                   {"uri", "data:application/octet-stream;base64," + base64(bytes_)}}}},
                {"bufferViews", views_},
                {"accessors", accessors_},
                {"meshes", std::move(meshes)},
                {"nodes", std::move(nodes)}};
    if (!scenes.is_null()) {
      doc["scenes"] = std::move(scenes);
      doc["scene"] = 0;
    }
    return doc;
  }

 private:
  std::vector<uint8_t> bytes_;
  json views_ = json::array();
  json accessors_ = json::array();
};

inline json triangleMesh(int position, std::optional<int> indices = std::nullopt, int mode = 4,
                  std::optional<int> normal = std::nullopt) {
  json prim = {{"attributes", {{"POSITION", position}}}, {"mode", mode}};
  if (indices) prim["indices"] = *indices;
  if (normal) prim["attributes"]["NORMAL"] = *normal;
  return json::array({{{"name", "tri"}, {"primitives", {prim}}}});
}

inline const std::vector<glm::vec3> kTriangle = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};  // counter-clockwise seen from +Z

class GltfImportTest : public TempDirTest {
 protected:
  std::string writeText(const std::string& name, const std::string& text) {
    const std::filesystem::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << text;
    return path.string();
  }
  std::string writeBytes(const std::string& name, const std::vector<uint8_t>& bytes) {
    const std::filesystem::path path = dir_ / name;
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    return path.string();
  }
  std::string write(const std::string& name, const json& doc) { return writeText(name, doc.dump(1)); }

};

}  // namespace visbuf::test
