// Shared helpers of the GPU tests: one validation-enabled device per process, image comparison.
#pragma once

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "visbuf/asset/texture_bake.h"
#include "visbuf/core/image_compare.h"
#include "visbuf/core/image_io.h"
#include "visbuf/gpu/device.h"
#include "visbuf/render/renderer.h"

namespace visbuf::test {

// Whether this build decodes images (VISBUF_WITH_OIIO): without it every image step reports Unsupported, and
// the tests that bake textures from PNG/JPEG skip with REQUIRE_IMAGE_DECODING() instead of failing.
inline bool imageDecodingBuilt() {
  LinearImage one;
  one.width = one.height = 1;
  one.rgba = {0.0f, 0.0f, 0.0f, 1.0f};
  Result<LinearImage> r = resizeImage(one, 1, 1);
  return r.ok() || r.error().code != ErrorCode::Unsupported;
}
#define REQUIRE_IMAGE_DECODING()                                                                          \
  do {                                                                                                    \
    if (!::visbuf::test::imageDecodingBuilt())                                                            \
      GTEST_SKIP() << "built without OpenImageIO (VISBUF_WITH_OIIO=OFF): this test bakes textures from images"; \
  } while (0)

// The device every GPU test uses: default selection (lavapipe in CI), validation layers on.
inline gpu::Device& testDevice() {
  static std::unique_ptr<gpu::Device> device = [] {
    gpu::DeviceOptions o;
    o.validation = true;
    o.verbose = false;
    const char* env = std::getenv("VISBUF_TEST_DEVICE");
    if (env) {
      auto p = gpu::parseDeviceOption(env, o);
      if (p.ok()) o = *p;
    }
    auto d = gpu::Device::create(o);
    if (!d.ok()) {
      std::fprintf(stderr, "GPU tests need a Vulkan device: %s\n", d.error().message.c_str());
      std::abort();
    }
    return std::move(d.value());
  }();
  return *device;
}

// Fails the current test if the validation layers reported anything since `before`.
#define EXPECT_NO_VALIDATION_MESSAGES(before) \
  EXPECT_EQ(::visbuf::test::testDevice().validationMessages(), (before)) << "Vulkan validation reported messages"

using ::visbuf::ImageError;
using ::visbuf::compareColor;

// One camera's visbuf and forward frames (LOD off, with IDs and colour): the inputs of the coverage, colour and
// per-pixel judge comparisons.
inline std::pair<Result<FrameResult>, Result<FrameResult>> renderBothPaths(Renderer& renderer, const Camera& cam) {
  FrameOptions fo;
  fo.lodErrorPixels = 0.0f;
  fo.readIds = true;
  fo.path = RenderPath::Visbuf;
  auto vis = renderer.renderFrame(cam, fo);
  fo.path = RenderPath::Forward;
  return {std::move(vis), renderer.renderFrame(cam, fo)};
}

// Where a test fails, it leaves the images behind for a person to look at.
inline void saveOnFailure(const std::string& name, const FrameResult& a, const FrameResult& b) {
  if (!::testing::Test::HasFailure()) return;
  (void)writeColorImage(name + ".actual.png", a.width, a.height, a.color);
  (void)writeColorImage(name + ".reference.png", b.width, b.height, b.color);
  std::vector<float> diff(a.color.size());
  for (size_t i = 0; i < diff.size(); ++i) diff[i] = i % 4 == 3 ? 1.0f : std::abs(a.color[i] - b.color[i]) * 8.0f;
  (void)writeColorImage(name + ".diff.png", a.width, a.height, diff);
}

}  // namespace visbuf::test
