// Where the tests find glTF assets: the repository's own assets/ (VISBUF_ASSETS_DIR, complete in every
// clone), then any larger corpus named by the environment variable VISBUF_EXTRA_ASSETS (folders separated
// by ':', e.g. ../shared/assets; scripts/test.sh sets it when that folder exists).
#pragma once

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace visbuf::test {

// The repository's assets/ folder.
inline std::filesystem::path repoAssetsDir() {
#ifdef VISBUF_ASSETS_DIR
  return std::filesystem::path(VISBUF_ASSETS_DIR);
#else
  return std::filesystem::path("assets");
#endif
}

// The folders of VISBUF_EXTRA_ASSETS that exist (none when it is unset).
inline std::vector<std::filesystem::path> extraAssetDirs() {
  std::vector<std::filesystem::path> dirs;
  const char* env = std::getenv("VISBUF_EXTRA_ASSETS");
  if (!env) return dirs;
  std::string list = env;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t end = std::min(list.find(':', start), list.size());
    const std::string dir = list.substr(start, end - start);
    if (!dir.empty() && std::filesystem::is_directory(dir)) dirs.emplace_back(dir);
    start = end + 1;
  }
  return dirs;
}

// Every asset folder to sweep: assets/ first, then the extra corpora.
inline std::vector<std::filesystem::path> assetDirs() {
  std::vector<std::filesystem::path> dirs{repoAssetsDir()};
  for (const auto& d : extraAssetDirs()) dirs.push_back(d);
  return dirs;
}

// An asset of the extra corpus only (nullopt when no extra folder has it).
inline std::optional<std::filesystem::path> extraAsset(const std::string& relative) {
  for (const auto& d : extraAssetDirs())
    if (std::filesystem::exists(d / relative)) return d / relative;
  return std::nullopt;
}

// An asset by its path relative to an asset folder: assets/ when it has it, else the first extra
// corpus that does, else the (missing) path under assets/ so that REQUIRE_ASSET names it.
inline std::filesystem::path assetPath(const std::string& relative) {
  const std::filesystem::path repo = repoAssetsDir() / relative;
  if (std::filesystem::exists(repo)) return repo;
  if (auto extra = extraAsset(relative)) return *extra;
  return repo;
}

// Base64 (RFC 4648, padded) for the data: URIs of generated glTF fixtures.
inline std::string base64(const std::vector<uint8_t>& data) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < data.size(); i += 3) {
    const uint32_t b0 = data[i];
    const uint32_t b1 = i + 1 < data.size() ? data[i + 1] : 0;
    const uint32_t b2 = i + 2 < data.size() ? data[i + 2] : 0;
    const uint32_t triple = (b0 << 16) | (b1 << 8) | b2;
    out += kAlphabet[(triple >> 18) & 63];
    out += kAlphabet[(triple >> 12) & 63];
    out += i + 1 < data.size() ? kAlphabet[(triple >> 6) & 63] : '=';
    out += i + 2 < data.size() ? kAlphabet[triple & 63] : '=';
  }
  return out;
}

// A binary glTF (.glb) of a JSON chunk (padded with spaces) and, unless `bin` is empty, a BIN chunk (padded with
// zeros), little-endian as the container's specification has it.
inline std::vector<uint8_t> makeGlb(const std::string& jsonText, const std::vector<uint8_t>& bin) {
  std::string jsonChunk = jsonText;
  while (jsonChunk.size() % 4 != 0) jsonChunk += ' ';
  std::vector<uint8_t> binChunk = bin;
  while (binChunk.size() % 4 != 0) binChunk.push_back(0);
  std::vector<uint8_t> out;
  auto put32 = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
  };
  put32(0x46546C67);  // "glTF"
  put32(2);
  put32(static_cast<uint32_t>(12 + 8 + jsonChunk.size() + (binChunk.empty() ? 0 : 8 + binChunk.size())));
  put32(static_cast<uint32_t>(jsonChunk.size()));
  put32(0x4E4F534A);  // "JSON"
  out.insert(out.end(), jsonChunk.begin(), jsonChunk.end());
  if (!binChunk.empty()) {
    put32(static_cast<uint32_t>(binChunk.size()));
    put32(0x004E4942);  // "BIN\0"
    out.insert(out.end(), binChunk.begin(), binChunk.end());
  }
  return out;
}

// Registers `suite.name` only when an extra corpus has `relative` (so a clone without one runs the test
// neither as a pass nor as a skip); the body receives the asset's path. ctest discovers the tests when it
// runs them (DISCOVERY_MODE PRE_TEST), so VISBUF_EXTRA_ASSETS is read from ctest's environment.
template <class Body>
bool registerExtraAssetTest(const char* suite, const char* name, const char* relative, const char* file, int line,
                            Body body) {
  const std::optional<std::filesystem::path> path = extraAsset(relative);
  if (!path) return false;
  class ExtraAssetTest : public ::testing::Test {
   public:
    ExtraAssetTest(Body b, std::filesystem::path p) : body_(b), path_(std::move(p)) {}
    void TestBody() override { body_(path_); }

   private:
    Body body_;
    std::filesystem::path path_;
  };
  ::testing::RegisterTest(suite, name, nullptr, nullptr, file, line,
                          [body, p = *path]() -> ::testing::Test* { return new ExtraAssetTest(body, p); });
  return true;
}

}  // namespace visbuf::test

// EXTRA_ASSET_TEST(Suite, Name, "DamagedHelmet/glTF-Binary/DamagedHelmet.glb") { ... use `asset` ... }
#define EXTRA_ASSET_TEST(suite, name, relative)                                                             \
  static void suite##_##name##_Body(const std::filesystem::path& asset);                                    \
  [[maybe_unused]] static const bool suite##_##name##_Registered = ::visbuf::test::registerExtraAssetTest( \
      #suite, #name, relative, __FILE__, __LINE__, &suite##_##name##_Body);                                \
  static void suite##_##name##_Body(const std::filesystem::path& asset)

// An asset the repository ships: its absence is a broken checkout, so the test fails (never skips).
#define REQUIRE_ASSET(path)                                                                            \
  do {                                                                                                 \
    if (!std::filesystem::exists(path)) FAIL() << "asset missing from the checkout's assets/: " << (path); \
  } while (0)
