// Where the unit tests find the team's shared glTF assets (../shared/assets, through the
// VISBUF_SHARED_ASSETS_DIR define), and the skip when one is absent.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace visbuf::test {

inline std::filesystem::path assetPath(const std::string& relative) {
#ifdef VISBUF_SHARED_ASSETS_DIR
  return std::filesystem::path(VISBUF_SHARED_ASSETS_DIR) / relative;
#else
  return std::filesystem::path(relative);
#endif
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

}  // namespace visbuf::test

#define REQUIRE_ASSET(path)                                                              \
  do {                                                                                   \
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "asset not found: " << (path);   \
  } while (0)
