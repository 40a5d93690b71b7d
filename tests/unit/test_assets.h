// Where the unit tests find the team's shared glTF assets (../shared/assets, through the
// VISBUF_SHARED_ASSETS_DIR define), and the skip when one is absent.
#pragma once

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace visbuf::test {

inline std::filesystem::path assetPath(const std::string& relative) {
#ifdef VISBUF_SHARED_ASSETS_DIR
  return std::filesystem::path(VISBUF_SHARED_ASSETS_DIR) / relative;
#else
  return std::filesystem::path(relative);
#endif
}

}  // namespace visbuf::test

#define REQUIRE_ASSET(path)                                                              \
  do {                                                                                   \
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "asset not found: " << (path);   \
  } while (0)
