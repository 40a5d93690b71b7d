// Errors a host can handle (renderer.h, gpu/check.h): a Vulkan failure inside a renderer's method comes back as
// an error -- no abort, no exception --, is logged once through the host's sink, and leaves the renderer lost:
// every later call is refused and naming the first failure, and destroying it is safe. A failure while creating a
// renderer or a device returns an error and leaves nothing behind. The failures are injected
// (gpu::testing::failCheck: the Nth VK_CHECK reports the result although its call succeeded), so the device itself
// stays usable, which the tests check by rendering with a renderer created afterwards.
#include <string>
#include <utility>
#include <vector>

#include "gpu_test_util.h"
#include "visbuf/core/log.h"
#include "visbuf/gpu/check.h"
#include "visbuf/scene/generate.h"

namespace visbuf {
namespace {

Scene smallField() {
  FieldParams p;
  p.objects = 50;
  p.extent = 10.0;
  return makeFieldScene(p).value();
}

Camera fieldCamera() {
  Camera c;
  c.position = {0.0, 5.0, 30.0};
  c.target = {0.0, 0.0, 0.0};
  return c;
}

constexpr RendererConfig kSmall{.width = 64, .height = 48};

// The messages logged while it lives (the previous sink restored after).
struct CapturedLog {
  std::vector<std::pair<LogLevel, std::string>> messages;
  LogSink previous;
  CapturedLog() {
    previous = setLogSink([this](LogLevel l, std::string_view m) { messages.emplace_back(l, std::string(m)); });
  }
  ~CapturedLog() { setLogSink(std::move(previous)); }
};

// A renderer created now renders (the device works after an injected failure).
void expectAFreshRendererRenders(gpu::Device& dev, const Scene& scene) {
  auto fresh = Renderer::create(dev, scene, kSmall);
  ASSERT_TRUE(fresh.ok()) << fresh.error().message;
  auto frame = (*fresh)->renderFrame(fieldCamera(), FrameOptions{});
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  EXPECT_GT(frame->stats.cull.drawsRendered, 0u);
}

GPU_TEST(Errors, VulkanFailureInAFrameComesBackAndLosesTheRenderer) {
  const Scene scene = smallField();
  auto renderer = Renderer::create(dev, scene, kSmall);
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  Renderer& r = **renderer;
  ASSERT_TRUE(r.renderFrame(fieldCamera(), FrameOptions{}).ok());
  EXPECT_FALSE(r.lost());

  CapturedLog log;
  gpu::testing::failCheck(2, VK_ERROR_DEVICE_LOST);  // the third check of the frame (recording it)
  auto failed = r.renderFrame(fieldCamera(), FrameOptions{});
  gpu::testing::disarm();
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.error().code, ErrorCode::DeviceLost);
  EXPECT_NE(failed.error().message.find("VK_ERROR_DEVICE_LOST"), std::string::npos) << failed.error().message;
  EXPECT_TRUE(r.lost());
  ASSERT_EQ(log.messages.size(), 1u);
  EXPECT_EQ(log.messages[0].first, LogLevel::Error);
  EXPECT_NE(log.messages[0].second.find("VK_ERROR_DEVICE_LOST"), std::string::npos) << log.messages[0].second;

  // Every later call that would touch the GPU is refused, naming the first failure.
  auto again = r.renderFrame(fieldCamera(), FrameOptions{});
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.error().code, ErrorCode::DeviceLost);
  EXPECT_NE(again.error().message.find("unusable after an earlier failure"), std::string::npos);
  EXPECT_NE(again.error().message.find("VK_ERROR_DEVICE_LOST"), std::string::npos);
  EXPECT_FALSE(r.resize(32, 32).ok());
  EXPECT_FALSE(r.setVisible(0, false).ok());
  EXPECT_FALSE(r.record(FrameInputs{fieldCamera(), {}}).ok());
  EXPECT_EQ(log.messages.size(), 1u) << "a refused call is not a new failure";
  renderer.value().reset();  // destroying a lost renderer is safe (and leaves no validation message)

  expectAFreshRendererRenders(dev, scene);
}

// Every checked call of a renderer's creation, in turn, fails (every third one, and the first ones): each comes back
// as OutOfMemory, and what the creation had made is released -- checked on a device of the test's own, destroyed
// at the end with validation on: an object left behind is reported then ("has not been destroyed").
GPU_TEST(Errors, OutOfMemoryWhileCreatingARendererLeavesNothingBehind) {
  const Scene scene = smallField();
  CapturedLog log;
  uint32_t failures = 0;
  {
    gpu::DeviceOptions o;
    o.validation = true;
    o.verbose = false;
    auto own = gpu::Device::create(o);
    ASSERT_TRUE(own.ok()) << own.error().message;
    for (uint32_t after = 0;; after += after < 12 ? 1 : 3) {
      gpu::testing::failCheck(after, VK_ERROR_OUT_OF_DEVICE_MEMORY);
      auto r = Renderer::create(**own, scene, kSmall);
      gpu::testing::disarm();
      if (r.ok()) break;  // the creation makes fewer checked calls than `after`: every one was tried
      ++failures;
      ASSERT_EQ(r.error().code, ErrorCode::OutOfMemory) << "check " << after << ": " << r.error().message;
      ASSERT_NE(r.error().message.find("VK_ERROR_OUT_OF_DEVICE_MEMORY"), std::string::npos) << r.error().message;
      ASSERT_LT(after, 100000u);
    }
    expectAFreshRendererRenders(**own, scene);
  }  // the device is destroyed here: validation reports what was left behind
  EXPECT_GT(failures, 20u) << "the creation should make more checked calls than this";
  for (const auto& [level, message] : log.messages)
    ADD_FAILURE() << "logged while failing creations: " << logLevelName(level) << ": " << message;
  std::printf("%u failed creations (one per checked call), nothing left behind\n", failures);
}

GPU_TEST(Errors, DeviceCreationFailureIsAnError) {
  gpu::DeviceOptions o;
  o.verbose = false;
  gpu::testing::failCheck(0, VK_ERROR_INITIALIZATION_FAILED);
  auto d = gpu::Device::create(o);
  gpu::testing::disarm();
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.error().code, ErrorCode::VulkanError);
  EXPECT_NE(d.error().message.find("VK_ERROR_INITIALIZATION_FAILED"), std::string::npos) << d.error().message;
}

}  // namespace
}  // namespace visbuf
