// The texture tests' shared part (test_textures.cpp, test_material_import.cpp): random RGBA8 images and a fixture
// that writes PNGs with OpenImageIO at test time (no committed binaries); its tests skip in a build without
// OpenImageIO (REQUIRE_OIIO, a compile-time fact) and fail where an image cannot be written in a build with it.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "../build_config.h"
#include "temp_dir_test.h"
#include "visbuf/core/image_io.h"

namespace visbuf::test {

inline std::vector<uint8_t> randomRgba(uint32_t width, uint32_t height, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> rgba(size_t(width) * height * 4);
  for (uint8_t& v : rgba) v = uint8_t(rng() & 0xFF);
  return rgba;
}

inline std::vector<uint8_t> fileBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Writes PNGs with OpenImageIO at test time. In a build without it nothing is written (the test skips at its
// REQUIRE_OIIO()); in a build with it, a PNG that cannot be written fails the test.
class TextureTest : public TempDirTest {
 protected:
  std::filesystem::path writePng(const std::string& name, uint32_t width, uint32_t height,
                                 const std::vector<uint8_t>& rgba) {
    const std::filesystem::path path = dir_ / name;
    if constexpr (!kWithOiio) return path;
    Status s = writeRgba8Image(path.string(), width, height, rgba);
    EXPECT_TRUE(s) << s.error().message;
    return path;
  }
  std::vector<uint8_t> pngBytes(uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba) {
    return fileBytes(writePng("tmp.png", width, height, rgba));
  }
};

}  // namespace visbuf::test

// Skips the test in a build without OpenImageIO, and only there (tests/build_config.h).
#define REQUIRE_OIIO() SKIP_WITHOUT_OIIO()
