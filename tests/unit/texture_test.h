// The texture tests' shared part (test_textures.cpp, test_material_import.cpp): random RGBA8 images and a fixture
// that writes PNGs with OpenImageIO at test time (no committed binaries) and skips without it.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

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

// Writes PNGs with OpenImageIO at test time; REQUIRE_OIIO() skips a test where it could not.
class TextureTest : public TempDirTest {
 protected:
  std::filesystem::path writePng(const std::string& name, uint32_t width, uint32_t height,
                                 const std::vector<uint8_t>& rgba) {
    const std::filesystem::path path = dir_ / name;
    Status s = writeRgba8Image(path.string(), width, height, rgba);
    if (!s && s.error().code == ErrorCode::Unsupported) {
      noOiio_ = true;
      return path;
    }
    EXPECT_TRUE(s) << s.error().message;
    return path;
  }
  std::vector<uint8_t> pngBytes(uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba) {
    return fileBytes(writePng("tmp.png", width, height, rgba));
  }
  bool noOiio_ = false;
};

}  // namespace visbuf::test

#define REQUIRE_OIIO()                                                          \
  do {                                                                          \
    if (noOiio_) GTEST_SKIP() << "built without OpenImageIO (VISBUF_WITH_OIIO)"; \
  } while (0)
