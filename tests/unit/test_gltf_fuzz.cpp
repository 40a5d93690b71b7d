// The glTF import fuzzer (GltfFuzz.RandomMutationsNeverCrash): its mutation engine and driver, ~1,500 random
// mutations of small valid files through importGltfScene, importGltfMesh and buildImportedScene. The generated
// seed files and the minimized regressions it found are in test_gltf_fuzz_inputs.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
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

#include "gltf_fuzz_helpers.h"
#include "test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/generate.h"
#include "visbuf/scene/scene.h"

namespace visbuf {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

using test::makeGlb;
using test::gltf_fuzz::GltfFuzz;
using test::gltf_fuzz::makeDataUriGltf;
using test::gltf_fuzz::makeSkinnedGlb;
using test::gltf_fuzz::writeFile;

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
//
// gltf_import.h promises that nothing in a file's contents can make the importer assert or crash. Follows
// PackFuzz in test_pack.cpp: a fixed seed, a fixed number of iterations, every call must return (ok, or an Error
// with a message), counts printed; scripts/test.sh also runs it under ASan/UBSan. Seeds: the two generated files
// of test_gltf_fuzz_inputs.cpp, plus a few small sample assets of the repository's assets/ when they are present
// (their external .bin files are copied next to the mutated file).

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

}  // namespace
}  // namespace visbuf
