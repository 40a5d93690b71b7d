// Shared helpers of the GPU tests: one validation-enabled device per process, image comparison.
#pragma once

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/image_io.h"
#include "gpu/device.h"
#include "render/renderer.h"

namespace visbuf::test {

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

struct ImageError {
  double maxAbs = 0.0;
  double meanAbs = 0.0;
  double psnr = INFINITY;
  size_t differing = 0;  // pixels whose max channel error > 1/255
};

inline ImageError compareColor(const std::vector<float>& a, const std::vector<float>& b) {
  ImageError e;
  double sumSq = 0.0, sum = 0.0;
  const size_t pixels = a.size() / 4;
  for (size_t p = 0; p < pixels; ++p) {
    double worst = 0.0;
    for (int c = 0; c < 3; ++c) {
      double d = std::abs(double(std::clamp(a[p * 4 + c], 0.0f, 1.0f)) - double(std::clamp(b[p * 4 + c], 0.0f, 1.0f)));
      worst = std::max(worst, d);
      sumSq += d * d;
      sum += d;
    }
    e.maxAbs = std::max(e.maxAbs, worst);
    if (worst > 1.0 / 255.0) ++e.differing;
  }
  e.meanAbs = sum / double(pixels * 3);
  double mse = sumSq / double(pixels * 3);
  e.psnr = mse > 0 ? 10.0 * std::log10(1.0 / mse) : INFINITY;
  return e;
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
