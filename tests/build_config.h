// Facts about the build that decide which tests run, as compile definitions of the test targets
// (tests/CMakeLists.txt). A test skips on one of these only: never on a result of the code under test (an
// `Unsupported` from a bake would turn a regression into a skip).
#pragma once

#include <gtest/gtest.h>

// VISBUF_WITH_OIIO (1 or 0): the engine decodes and writes images through OpenImageIO. Without it every image
// step reports Unsupported by design; with it, an Unsupported from an image step is a failure.
#ifndef VISBUF_WITH_OIIO
#error "tests/CMakeLists.txt defines VISBUF_WITH_OIIO (1 or 0) for every test target"
#endif

namespace visbuf::test {
inline constexpr bool kWithOiio = VISBUF_WITH_OIIO != 0;
}  // namespace visbuf::test

// In a test body: skips the test in a build without OpenImageIO (and only there).
#define SKIP_WITHOUT_OIIO()                                                                        \
  do {                                                                                             \
    if constexpr (!::visbuf::test::kWithOiio)                                                      \
      GTEST_SKIP() << "built without OpenImageIO (VISBUF_WITH_OIIO=OFF): this test decodes images"; \
  } while (0)
