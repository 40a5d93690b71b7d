// Shared helpers of the GPU tests: one validation-enabled device per process, the fixture that checks its validation
// messages, image comparison.
#pragma once

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "../build_config.h"
#include "../unit/test_assets.h"
#include "visbuf/core/image_compare.h"
#include "visbuf/core/image_io.h"
#include "visbuf/gpu/device.h"
#include "visbuf/render/renderer.h"

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

// The fixture of every GPU test: the test device as `dev`, and no validation message from the test's set-up to its
// tear-down (the body's objects are destroyed by then, so a message at destruction counts too). A fixture of its own
// derives from GpuFixture<Base> (its members are destroyed after TearDown: reset those that touch the device in
// its own TearDown, before GpuFixture's).
template <class Base = ::testing::Test>
class GpuFixture : public Base {
 protected:
  void SetUp() override {
    Base::SetUp();
    messagesBefore_ = dev.validationMessages();
  }
  void TearDown() override {
    EXPECT_EQ(dev.validationMessages(), messagesBefore_)
        << "Vulkan validation reported messages (logged above as 'visbuf: warning/error: validation: ...')";
    Base::TearDown();
  }
  gpu::Device& dev = testDevice();

 private:
  uint32_t messagesBefore_ = 0;
};
using GpuTest = GpuFixture<>;

// GPU_TEST(Suite, Name): a test with the GpuTest fixture under the suite name given (TEST_F would name the suite
// after the fixture). Every test of a suite is a GPU_TEST, or a TEST_F of one fixture derived from GpuFixture.
#define GPU_TEST(suite, name) \
  GTEST_TEST_(suite, name, ::visbuf::test::GpuTest, ::testing::internal::GetTypeId<::visbuf::test::GpuTest>())

// GPU_EXTRA_ASSET_TEST(Suite, Name, "relative/path") { ... use `asset` ... }: EXTRA_ASSET_TEST (registered only when
// an extra corpus has the asset, ../unit/test_assets.h) with the GpuTest fixture, so that it shares its suite with
// GPU_TESTs and its validation messages are checked. The body is a function: it takes the device from testDevice().
template <class Body>
bool registerGpuExtraAssetTest(const char* suite, const char* name, const char* relative, const char* file, int line,
                               Body body) {
  const std::optional<std::filesystem::path> path = extraAsset(relative);
  if (!path) return false;
  class ExtraAssetTest : public GpuTest {
   public:
    ExtraAssetTest(Body b, std::filesystem::path p) : body_(b), path_(std::move(p)) {}
    void TestBody() override { body_(path_); }

   private:
    Body body_;
    std::filesystem::path path_;
  };
  // (The factory's return type is the fixture gtest files the test under: GpuTest, as for GPU_TEST.)
  ::testing::RegisterTest(suite, name, nullptr, nullptr, file, line,
                          [body, p = *path]() -> GpuTest* { return new ExtraAssetTest(body, p); });
  return true;
}

#define GPU_EXTRA_ASSET_TEST(suite, name, relative)                                                            \
  static void suite##_##name##_Body(const std::filesystem::path& asset);                                       \
  [[maybe_unused]] static const bool suite##_##name##_Registered = ::visbuf::test::registerGpuExtraAssetTest( \
      #suite, #name, relative, __FILE__, __LINE__, &suite##_##name##_Body);                                   \
  static void suite##_##name##_Body(const std::filesystem::path& asset)

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
