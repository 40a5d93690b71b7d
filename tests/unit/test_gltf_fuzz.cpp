// Bounded-time fuzzing of the glTF import path (importGltfScene, importGltfMesh and, for the scenes that
// import, buildImportedScene): gltf_import.h promises that nothing in a file's contents can make the importer
// assert or crash. Follows PackFuzz in test_pack.cpp: a fixed seed, a fixed number of iterations, every call
// must return (ok, or an Error with a message), counts printed; scripts/test.sh also runs it under ASan/UBSan.
//
// Seeds: two small files written here (a .glb with an indexed, skinned, morphed, animated, textured mesh, and a
// .gltf whose buffer is a data: URI), plus a few small sample assets of the repository's assets/ when they
// are present (their external .bin files are copied next to the mutated file).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "test_assets.h"
#include "temp_dir_test.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/generate.h"
#include "visbuf/scene/scene.h"

namespace visbuf {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr int kUByte = 5121;
constexpr int kUShort = 5123;
constexpr int kFloat = 5126;

// --- seed files
// ---------------------------------------------------------------------------------------------

// One binary buffer with bufferViews and accessors appended to a JSON document.
class BinBuilder {
 public:
  explicit BinBuilder(json& doc) : doc_(doc) {}

  template <typename T>
  int view(const std::vector<T>& values, std::optional<int> byteStride = std::nullopt) {
    while (bytes_.size() % 4 != 0) bytes_.push_back(0);
    const size_t offset = bytes_.size();
    bytes_.resize(offset + values.size() * sizeof(T));
    std::memcpy(bytes_.data() + offset, values.data(), values.size() * sizeof(T));
    json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * sizeof(T)}};
    if (byteStride) v["byteStride"] = *byteStride;
    doc_["bufferViews"].push_back(v);
    return static_cast<int>(doc_["bufferViews"].size()) - 1;
  }
  int accessor(json a) {
    doc_["accessors"].push_back(std::move(a));
    return static_cast<int>(doc_["accessors"].size()) - 1;
  }
  template <typename T>
  int add(const std::vector<T>& values, int componentType, const char* type, size_t count, bool normalized = false) {
    json a = {{"bufferView", view(values)}, {"componentType", componentType}, {"count", count}, {"type", type}};
    if (normalized) a["normalized"] = true;
    return accessor(std::move(a));
  }
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  json& doc_;
  std::vector<uint8_t> bytes_;
};

using test::makeGlb;
using test::base64;

// A .glb: an indexed quad skinned to a 2-joint chain (node 0), the same quad with a sparse morph target under
// a mirroring node (node 3), a material with an embedded texture, and an animation with LINEAR rotation, STEP
// translation and weights channels.
std::vector<uint8_t> makeSkinnedGlb() {
  json doc = {{"asset", {{"version", "2.0"}}}, {"scene", 0}};
  BinBuilder b(doc);
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const int pos = b.accessor({{"bufferView", b.view(positions)},
                              {"componentType", kFloat},
                              {"count", 4},
                              {"type", "VEC3"},
                              {"min", {0, 0, 0}},
                              {"max", {1, 1, 0}}});
  const int nrm = b.add(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, kFloat, "VEC3", 4);
  const int uv = b.add(std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}, kFloat, "VEC2", 4);
  const int joints = b.add(std::vector<uint8_t>{0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0}, kUByte, "VEC4", 4);
  const int weights =
      b.add(std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, 0.5f, 0.5f, 0, 0, 0.25f, 0.75f, 0, 0}, kFloat, "VEC4", 4);
  const int idx = b.add(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}, kUShort, "SCALAR", 6);
  std::vector<float> ibm(32, 0.0f);
  for (int m = 0; m < 2; ++m)
    for (int d = 0; d < 4; ++d) ibm[size_t(16 * m + 5 * d)] = 1.0f;
  ibm[16 + 13] = -1.0f;  // joint 1 sits at y = 1
  const int ibmAcc = b.add(ibm, kFloat, "MAT4", 2);
  // Sparse morph target: no bufferView, vertex 2 moves by +z.
  const int sparseIdx = b.view(std::vector<uint8_t>{2});
  const int sparseVal = b.view(std::vector<float>{0, 0, 0.5f});
  const int morph = b.accessor({{"componentType", kFloat},
                                {"count", 4},
                                {"type", "VEC3"},
                                {"sparse",
                                 {{"count", 1},
                                  {"indices", {{"bufferView", sparseIdx}, {"componentType", kUByte}}},
                                  {"values", {{"bufferView", sparseVal}}}}}});
  const int times = b.add(std::vector<float>{0, 1}, kFloat, "SCALAR", 2);
  const int rot = b.add(std::vector<float>{0, 0, 0, 1, 0, 0, 0.38268343f, 0.92387953f}, kFloat, "VEC4", 2);
  const int trans = b.add(std::vector<float>{0, 0, 0, 0.5f, 0, 0}, kFloat, "VEC3", 2);
  const int wts = b.add(std::vector<float>{0, 1}, kFloat, "SCALAR", 2);
  const int image = b.view(std::vector<uint8_t>{0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A});

  doc["meshes"] = json::array(
      {{{"name", "skinned"},
        {"primitives",
         {{{"attributes",
            {{"POSITION", pos}, {"NORMAL", nrm}, {"TEXCOORD_0", uv}, {"JOINTS_0", joints}, {"WEIGHTS_0", weights}}},
           {"indices", idx},
           {"material", 0}}}}},
       {{"name", "morphed"},
        {"weights", {0.5}},
        {"primitives",
         {{{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}},
           {"indices", idx},
           {"material", 0},
           {"targets", {{{"POSITION", morph}}}}}}}}});
  doc["nodes"] = json::array({{{"name", "skinned"}, {"mesh", 0}, {"skin", 0}},
                              {{"name", "root"}, {"translation", {0, 0, 0}}, {"children", {2}}},
                              {{"name", "tip"}, {"translation", {0, 1, 0}}},
                              {{"name", "mirror"}, {"mesh", 1}, {"scale", {-1, 1, 1}}, {"translation", {3, 0, 0}}}});
  doc["scenes"] = json::array({{{"nodes", {0, 1, 3}}}});
  doc["skins"] = json::array({{{"joints", {1, 2}}, {"inverseBindMatrices", ibmAcc}, {"skeleton", 1}}});
  doc["animations"] = json::array(
      {{{"name", "wave"},
        {"samplers",
         {{{"input", times}, {"output", rot}},
          {{"input", times}, {"output", trans}, {"interpolation", "STEP"}},
          {{"input", times}, {"output", wts}}}},
        {"channels",
         {{{"sampler", 0}, {"target", {{"node", 2}, {"path", "rotation"}}}},
          {{"sampler", 1}, {"target", {{"node", 1}, {"path", "translation"}}}},
          {{"sampler", 2}, {"target", {{"node", 3}, {"path", "weights"}}}}}}}});
  doc["materials"] = json::array({{{"name", "mat"},
                                   {"pbrMetallicRoughness",
                                    {{"baseColorFactor", {1, 0.5, 0.25, 1}},
                                     {"metallicFactor", 0.5},
                                     {"roughnessFactor", 0.5},
                                     {"baseColorTexture", {{"index", 0}}}}},
                                   {"normalTexture", {{"index", 0}, {"scale", 1}}},
                                   {"alphaMode", "MASK"},
                                   {"alphaCutoff", 0.3},
                                   {"doubleSided", true}}});
  doc["images"] = json::array({{{"bufferView", image}, {"mimeType", "image/png"}}});
  doc["samplers"] = json::array({{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 33648}}});
  doc["textures"] = json::array({{{"source", 0}, {"sampler", 0}}});
  doc["buffers"] = json::array({{{"byteLength", b.bytes().size()}}});
  return makeGlb(doc.dump(), b.bytes());
}

// A .gltf with its buffer as a data: URI: interleaved position+normal (byteStride 24), quantized uvs and
// colours, tangents, u8 indices, a TRIANGLES and a TRIANGLE_STRIP primitive, a matrix parent and a TRS child.
std::string makeDataUriGltf() {
  json doc = {{"asset", {{"version", "2.0"}}}};
  BinBuilder b(doc);
  const std::vector<float> interleaved = {0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 1, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1};
  const int view = b.view(interleaved, 24);
  const int pos = b.accessor({{"bufferView", view},
                              {"componentType", kFloat},
                              {"count", 4},
                              {"type", "VEC3"},
                              {"min", {0, 0, 0}},
                              {"max", {1, 1, 0}}});
  const int nrm = b.accessor({{"bufferView", view}, {"byteOffset", 12}, {"componentType", kFloat}, {"count", 4},
                              {"type", "VEC3"}});
  const int uv = b.add(std::vector<uint16_t>{0, 0, 65535, 0, 65535, 65535, 0, 65535}, kUShort, "VEC2", 4, true);
  const int color = b.add(std::vector<uint8_t>{255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128},
                          kUByte, "VEC4", 4, true);
  const int tangent = b.add(std::vector<float>{1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1}, kFloat, "VEC4", 4);
  const int idx = b.add(std::vector<uint8_t>{0, 1, 2, 0, 2, 3}, kUByte, "SCALAR", 6);
  const int strip = b.add(std::vector<uint8_t>{0, 1, 3, 2}, kUByte, "SCALAR", 4);
  const json attributes = {
      {"POSITION", pos}, {"NORMAL", nrm}, {"TEXCOORD_0", uv}, {"COLOR_0", color}, {"TANGENT", tangent}};
  doc["meshes"] = json::array({{{"name", "quad"},
                                {"primitives",
                                 {{{"attributes", attributes}, {"indices", idx}, {"material", 0}},
                                  {{"attributes", attributes}, {"indices", strip}, {"mode", 5}}}}}});
  doc["nodes"] = json::array(
      {{{"name", "parent"}, {"matrix", {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 1, 2, 3, 1}}, {"children", {1}}},
       {{"name", "child"},
        {"mesh", 0},
        {"rotation", {0, 0.70710678, 0, 0.70710678}},
        {"scale", {1, 2, 1}},
        {"translation", {0, 0, -1}}}});
  doc["scenes"] = json::array({{{"nodes", {0}}}});
  doc["scene"] = 0;
  doc["materials"] = json::array({{{"name", "plain"},
                                   {"emissiveFactor", {0.1, 0.2, 0.3}},
                                   {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}}});
  doc["buffers"] = json::array(
      {{{"byteLength", b.bytes().size()}, {"uri", "data:application/octet-stream;base64," + base64(b.bytes())}}});
  return doc.dump(1);
}

// --- mutations
// ---------------------------------------------------------------------------------------------

const uint64_t kExtremes[] = {0, 1, 3, 4, 0x7F, 0xFF, 0xFFFF, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFC, 0xFFFFFFFF};

// Replacements for a numeric JSON token.
const char* const kNumbers[] = {"-1",       "0",          "1",       "4294967295", "4294967296", "2147483647",
                                "-2147483648", "1e308",   "-1e308",  "1e999",      "NaN",        "Infinity",
                                "-Infinity", "nan",       "1e-320",  "0.5",        "-0",         "65536",
                                "18446744073709551615",   "99999999999999999999999999", "5126", "5121", "34962"};

class Mutator {
 public:
  explicit Mutator(uint64_t seed) : rng_(seed) {}
  uint64_t below(uint64_t n) { return n == 0 ? 0 : rng_.next() % n; }
  uint64_t next() { return rng_.next(); }

  // One random edit of JSON text. Mostly edits that keep the JSON well-formed (numbers replaced or swapped),
  // so that most files get past the parser to the importer's own checks.
  void mutateText(std::string& s) {
    if (s.empty()) return;
    const uint64_t kind = below(13);
    switch (kind < 6 ? 0 : kind < 9 ? 3 : kind - 5) {
      case 0: {  // replace a number
        const std::vector<std::pair<size_t, size_t>> numbers = numberTokens(s);
        if (numbers.empty()) break;
        const auto [at, len] = numbers[below(numbers.size())];
        s.replace(at, len, kNumbers[below(std::size(kNumbers))]);
        break;
      }
      case 3: {  // swap the values of two "count" / "byteOffset" / "byteStride" / "componentType" / ... keys
        const std::vector<std::pair<size_t, size_t>> values = keyedValues(s);
        if (values.size() < 2) break;
        auto a = values[below(values.size())], c = values[below(values.size())];
        if (a.first == c.first) break;
        if (a.first > c.first) std::swap(a, c);
        const std::string va = s.substr(a.first, a.second), vc = s.substr(c.first, c.second);
        s.replace(c.first, c.second, va);  // the later one first: the earlier offsets stay valid
        s.replace(a.first, a.second, vc);
        break;
      }
      case 4: {  // delete a few characters
        const size_t at = below(s.size());
        s.erase(at, 1 + below(8));
        break;
      }
      case 5: {  // duplicate a run of characters
        const size_t at = below(s.size());
        const std::string run = s.substr(at, 1 + below(16));
        s.insert(at, run);
        break;
      }
      case 6: {  // break a bracket: delete it, replace it, or add one
        std::vector<size_t> brackets;
        for (size_t i = 0; i < s.size(); ++i)
          if (s[i] == '{' || s[i] == '}' || s[i] == '[' || s[i] == ']') brackets.push_back(i);
        if (brackets.empty()) break;
        const size_t at = brackets[below(brackets.size())];
        static const char kBrackets[] = "{}[]";
        switch (below(3)) {
          case 0: s.erase(at, 1); break;
          case 1: s[at] = kBrackets[below(4)]; break;
          default: s.insert(at, 1, kBrackets[below(4)]); break;
        }
        break;
      }
      default: {  // a random printable or control byte
        s[below(s.size())] = static_cast<char>(below(3) == 0 ? next() : 32 + below(95));
        break;
      }
    }
  }

  // One random edit of a GLB (`jsonEnd` = end of the JSON chunk, where the BIN chunk header starts).
  void mutateGlb(std::vector<uint8_t>& v, size_t jsonEnd) {
    if (v.empty()) return;
    const uint64_t front = std::min<uint64_t>(v.size(), 64);
    switch (below(6)) {
      case 0: {  // bit flip, biased towards the headers
        const uint64_t at = below(below(3) == 0 ? front : v.size());
        v[at] ^= uint8_t(1u << below(8));
        break;
      }
      case 1:  // random byte
        v[below(v.size())] = uint8_t(next());
        break;
      case 2: {  // extreme uint32 over a header field: magic, version, length, chunk lengths and types
        const size_t fields[] = {0, 4, 8, 12, 16, jsonEnd, jsonEnd + 4};
        const size_t at = fields[below(std::size(fields))];
        const uint32_t x = uint32_t(kExtremes[below(std::size(kExtremes))]);
        if (at + 4 <= v.size()) std::memcpy(v.data() + at, &x, 4);
        break;
      }
      case 3: {  // extreme uint32 in the BIN chunk (accessor data: indices, counts of sparse data, ...)
        if (jsonEnd + 8 + 4 > v.size()) break;
        const size_t at = (jsonEnd + 8 + below(v.size() - jsonEnd - 8 - 3)) & ~size_t{3};
        const uint32_t x = uint32_t(kExtremes[below(std::size(kExtremes))]);
        if (at + 4 <= v.size()) std::memcpy(v.data() + at, &x, 4);
        break;
      }
      case 4:  // truncation
        v.resize(below(v.size() + 1));
        break;
      default:  // extension
        v.resize(v.size() + 1 + below(32), uint8_t(next()));
        break;
    }
  }

 private:
  // (offset, length) of every number outside strings.
  static std::vector<std::pair<size_t, size_t>> numberTokens(const std::string& s) {
    std::vector<std::pair<size_t, size_t>> out;
    bool inString = false;
    for (size_t i = 0; i < s.size(); ++i) {
      const char c = s[i];
      if (inString) {
        if (c == '\\') {
          ++i;  // skip the escaped character
        } else if (c == '"') {
          inString = false;
        }
        continue;
      }
      if (c == '"') {
        inString = true;
      } else if (c == '-' || (c >= '0' && c <= '9')) {
        size_t j = i + 1;
        while (j < s.size() && (std::strchr("0123456789.eE+-", s[j]) != nullptr)) ++j;
        out.emplace_back(i, j - i);
        i = j - 1;
      }
    }
    return out;
  }
  // (offset, length) of the numeric values of the structural integer keys.
  static std::vector<std::pair<size_t, size_t>> keyedValues(const std::string& s) {
    std::vector<std::pair<size_t, size_t>> out;
    for (const char* key : {"\"count\"", "\"byteOffset\"", "\"byteStride\"", "\"componentType\"",
                            "\"byteLength\"", "\"bufferView\"", "\"mode\""}) {
      for (size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + 1)) {
        size_t i = at + std::strlen(key);
        while (i < s.size() && (s[i] == ' ' || s[i] == ':' || s[i] == '\n' || s[i] == '\t')) ++i;
        size_t j = i;
        while (j < s.size() && (s[j] == '-' || (s[j] >= '0' && s[j] <= '9'))) ++j;
        if (j > i) out.emplace_back(i, j - i);
      }
    }
    return out;
  }

  Rng rng_;
};

// --- the fuzz target
// --------------------------------------------------------------------------------------------

struct Seed {
  std::string label;
  std::string fileName;                                     // written into the temp folder
  std::vector<uint8_t> bytes;                               // the file itself
  std::vector<std::pair<std::string, std::vector<uint8_t>>> sidecars;  // external buffers (uri, bytes)
  bool glb = false;
  int iterations = 0;
};

struct Counts {
  size_t rejected = 0;     // importGltfScene failed
  size_t deep = 0;         // ... with well-formed JSON and GLB container (by tinygltf's or the importer's checks)
  size_t accepted = 0;     // importGltfScene succeeded
  size_t built = 0;        // ... and buildImportedScene succeeded (then validateScene passed)
  size_t meshAccepted = 0;  // importGltfMesh succeeded
  double slowestMs = 0.0;  // slowest single iteration
};

std::vector<uint8_t> readFile(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

void writeFile(const fs::path& path, const std::vector<uint8_t>& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// Imports `path` through every entry point; contract violations are recorded as test failures.
void importEverything(const fs::path& path, Counts& counts) {
  const std::string p = path.string();
  GltfImportReport report;
  Result<ImportedScene> scene = importGltfScene(p, {}, &report);
  if (!scene) {
    ++counts.rejected;
    EXPECT_FALSE(scene.error().message.empty());
    const std::string& message = scene.error().message;
    if (message.find("json.exception") == std::string::npos && message.find("GLB") == std::string::npos) {
      ++counts.deep;
    }
  } else {
    ++counts.accepted;
    for (const ImportedMesh& m : scene->meshes) {
      for (uint32_t i : m.source.indices) {
        if (i >= m.source.positions.size()) {
          ADD_FAILURE() << "scene mesh '" << m.source.name << "': index out of range";
          break;
        }
      }
    }
    Result<Scene> built = buildImportedScene(*scene);
    if (built) {
      ++counts.built;
      const Status valid = validateScene(*built);
      EXPECT_TRUE(valid) << valid.error().message;
    } else {
      EXPECT_FALSE(built.error().message.empty());
    }
  }
  Result<MeshSource> mesh = importGltfMesh(p);
  if (!mesh) {
    EXPECT_FALSE(mesh.error().message.empty());
  } else {
    ++counts.meshAccepted;
    EXPECT_EQ(mesh->normals.size(), mesh->positions.size());
    EXPECT_EQ(mesh->indices.size() % 3, 0u);
    for (uint32_t i : mesh->indices) {
      if (i >= mesh->positions.size()) {
        ADD_FAILURE() << "flattened mesh: index out of range";
        break;
      }
    }
  }
}

// Where the GLB's BIN chunk header starts (12 + 8 + JSON chunk length), or the file size.
size_t glbJsonEnd(const std::vector<uint8_t>& v) {
  if (v.size() < 20) return v.size();
  uint32_t len = 0;
  std::memcpy(&len, v.data() + 12, 4);
  return std::min<size_t>(v.size(), 20 + size_t(len));
}

Counts fuzzSeed(const Seed& seed, const fs::path& dir, uint64_t rngSeed) {
  Mutator mut(rngSeed);
  Counts counts;
  const fs::path folder = dir / seed.label;
  const fs::path path = folder / seed.fileName;
  // The GLB split into its JSON text and BIN chunk, for the mutations that edit the JSON and re-wrap it.
  std::string glbJson;
  std::vector<uint8_t> glbBin;
  if (seed.glb) {
    const size_t jsonEnd = glbJsonEnd(seed.bytes);
    glbJson.assign(seed.bytes.begin() + 20, seed.bytes.begin() + std::ptrdiff_t(jsonEnd));
    if (jsonEnd + 8 <= seed.bytes.size()) glbBin.assign(seed.bytes.begin() + std::ptrdiff_t(jsonEnd + 8), seed.bytes.end());
  }
  for (int iteration = 0; iteration < seed.iterations; ++iteration) {
    std::vector<uint8_t> bytes;
    std::vector<std::pair<std::string, std::vector<uint8_t>>> sidecars = seed.sidecars;
    const int mutations = 1 + int(mut.below(3));
    if (seed.glb) {
      if (mut.below(3) == 0) {  // edit the JSON chunk and re-wrap it with consistent lengths
        std::string text = glbJson;
        for (int m = 0; m < mutations; ++m) mut.mutateText(text);
        bytes = makeGlb(text, glbBin);
      } else {
        bytes = seed.bytes;
        const size_t jsonEnd = glbJsonEnd(seed.bytes);
        for (int m = 0; m < mutations && !bytes.empty(); ++m) mut.mutateGlb(bytes, jsonEnd);
      }
    } else {
      std::string text(seed.bytes.begin(), seed.bytes.end());
      for (int m = 0; m < mutations; ++m) mut.mutateText(text);
      bytes.assign(text.begin(), text.end());
      if (!sidecars.empty() && mut.below(6) == 0) {  // damage an external buffer too: truncate or extend it
        std::vector<uint8_t>& bin = sidecars[mut.below(sidecars.size())].second;
        bin.resize(mut.below(2) ? mut.below(bin.size() + 1) : bin.size() + 1 + mut.below(64), uint8_t(mut.next()));
      }
    }
    writeFile(path, bytes);
    for (const auto& [uri, data] : sidecars) writeFile(folder / uri, data);
    SCOPED_TRACE(seed.label + " iteration " + std::to_string(iteration));
    const auto start = std::chrono::steady_clock::now();
    importEverything(path, counts);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    counts.slowestMs = std::max(counts.slowestMs, ms);
    if (::testing::Test::HasFatalFailure()) break;
  }
  return counts;
}

// A sample asset (and the external buffers its JSON names) as a seed; nullopt when it is not there.
std::optional<Seed> assetSeed(const std::string& relative, int iterations) {
  const fs::path path = test::assetPath(relative);
  if (!fs::is_regular_file(path)) return std::nullopt;
  Seed seed;
  seed.label = path.stem().string() + (path.extension() == ".glb" ? "_glb" : "_gltf");
  seed.fileName = path.filename().string();
  seed.bytes = readFile(path);
  seed.glb = path.extension() == ".glb";
  seed.iterations = iterations;
  if (!seed.glb) {
    const json doc = json::parse(seed.bytes.begin(), seed.bytes.end(), nullptr, false);
    if (doc.is_discarded()) return std::nullopt;
    for (const json& buffer : doc.value("buffers", json::array())) {
      const std::string uri = buffer.value("uri", "");
      if (uri.empty() || uri.rfind("data:", 0) == 0) continue;
      seed.sidecars.emplace_back(uri, readFile(path.parent_path() / uri));
    }
  }
  return seed;
}

class GltfFuzz : public test::TempDirTest {};

// ~1,500 random mutations (fixed seeds) of small valid glTF files: GLB bit flips, random bytes, extreme uint32
// values over the header / chunk headers / BIN data, truncation and extension; JSON numbers replaced by
// extremes (-1, 0, 2^32-1, 1e308, NaN, ...), swapped count / byteOffset / byteStride / componentType values,
// deleted and duplicated characters, broken brackets. Every import must return (no crash, assert, hang or
// sanitizer report under the sanitizer build); an imported scene must build and validate, or fail cleanly.
TEST_F(GltfFuzz, RandomMutationsNeverCrash) {
  std::vector<Seed> seeds;
  {
    Seed s;
    s.label = "generated_glb";
    s.fileName = "fuzz.glb";
    s.bytes = makeSkinnedGlb();
    s.glb = true;
    s.iterations = 300;
    seeds.push_back(std::move(s));
  }
  {
    Seed s;
    s.label = "generated_gltf";
    s.fileName = "fuzz.gltf";
    const std::string text = makeDataUriGltf();
    s.bytes.assign(text.begin(), text.end());
    s.iterations = 300;
    seeds.push_back(std::move(s));
  }
  for (const char* asset : {"BoxInterleaved/glTF/BoxInterleaved.gltf", "BoxMeshopt/BoxMeshopt.glb",
                            "BoxMeshopt/BoxMeshopt.gltf", "SimpleSparseAccessor/glTF/SimpleSparseAccessor.gltf",
                            "TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf",
                            "RiggedSimple/glTF/RiggedSimple.gltf", "AnimatedMorphCube/glTF/AnimatedMorphCube.gltf"}) {
    if (std::optional<Seed> s = assetSeed(asset, 130)) seeds.push_back(std::move(*s));
  }

  // Every seed must import as it is: otherwise the mutations only exercise the first parse error.
  for (const Seed& seed : seeds) {
    const fs::path folder = dir_ / ("original_" + seed.label);
    writeFile(folder / seed.fileName, seed.bytes);
    for (const auto& [uri, data] : seed.sidecars) writeFile(folder / uri, data);
    Result<ImportedScene> s = importGltfScene((folder / seed.fileName).string());
    ASSERT_TRUE(s) << seed.label << ": " << s.error().message;
    Result<Scene> built = buildImportedScene(*s);
    ASSERT_TRUE(built) << seed.label << ": " << built.error().message;
  }

  const auto start = std::chrono::steady_clock::now();
  Counts total;
  int iterations = 0;
  for (size_t i = 0; i < seeds.size(); ++i) {
    const Counts c = fuzzSeed(seeds[i], dir_, 20250601 + i);
    std::printf("[          ] %-28s %4d mutations: %4zu rejected (%4zu past the syntax), %4zu accepted (%zu built), "
                "%4zu as one mesh; slowest %.1f ms\n",
                seeds[i].label.c_str(), seeds[i].iterations, c.rejected, c.deep, c.accepted, c.built,
                c.meshAccepted, c.slowestMs);
    total.rejected += c.rejected;
    total.deep += c.deep;
    total.accepted += c.accepted;
    total.built += c.built;
    total.meshAccepted += c.meshAccepted;
    iterations += seeds[i].iterations;
    if (HasFatalFailure()) return;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(total.rejected + total.accepted, size_t(iterations));
  EXPECT_GT(total.rejected, 0u);
  EXPECT_GT(total.accepted, 0u);
  EXPECT_GT(total.deep, size_t(iterations) / 4);  // a good share gets past the JSON / GLB syntax
  std::printf("[          ] %zu seeds, %d mutations in %.1f s: %zu rejected (%zu past the syntax), %zu accepted "
              "(%zu built), %zu as one mesh\n",
              seeds.size(), iterations, seconds, total.rejected, total.deep, total.accepted, total.built,
              total.meshAccepted);
}

// --- regressions (inputs the fuzzer found, minimized)
// ----------------------------------------------------------------------

// A node whose world matrix is not singular but nearly so (scale 1e-11 on every axis: det 1e-33) was imported
// as an instance, and validateScene() then rejected the built scene ("degenerate (zero-scale) transform").
// Found by a numeric-token mutation of the generated .gltf; the importer now skips |det| < 1e-30 too.
TEST_F(GltfFuzz, NearlySingularNodeIsSkipped) {
  json doc = {{"asset", {{"version", "2.0"}}}};
  BinBuilder b(doc);
  const int pos = b.accessor({{"bufferView", b.view(std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0})},
                              {"componentType", kFloat},
                              {"count", 3},
                              {"type", "VEC3"},
                              {"min", {0, 0, 0}},
                              {"max", {1, 1, 0}}});
  doc["meshes"] = json::array({{{"primitives", {{{"attributes", {{"POSITION", pos}}}}}}}});
  doc["nodes"] = json::array({{{"name", "tiny"}, {"mesh", 0}, {"scale", {1e-11, 1e-11, 1e-11}}},
                              {{"name", "plain"}, {"mesh", 0}}});
  doc["scenes"] = json::array({{{"nodes", {0, 1}}}});
  doc["buffers"] = json::array(
      {{{"byteLength", b.bytes().size()}, {"uri", "data:application/octet-stream;base64," + base64(b.bytes())}}});
  const std::string text = doc.dump();
  const fs::path path = dir_ / "tiny.gltf";
  writeFile(path, std::vector<uint8_t>(text.begin(), text.end()));

  GltfImportReport report;
  Result<ImportedScene> scene = importGltfScene(path.string(), {}, &report);
  ASSERT_TRUE(scene) << scene.error().message;
  ASSERT_EQ(scene->instances.size(), 1u);
  EXPECT_EQ(scene->instances[0].node, 1);
  EXPECT_TRUE(std::any_of(report.warnings.begin(), report.warnings.end(),
                          [](const std::string& w) { return w.find("singular") != std::string::npos; }));
  Result<Scene> built = buildImportedScene(*scene);
  ASSERT_TRUE(built) << built.error().message;
  const Status valid = validateScene(*built);
  EXPECT_TRUE(valid) << valid.error().message;
}

}  // namespace
}  // namespace visbuf
