// VK_CHECK: every Vulkan call that must succeed is checked in every build (release included). A failure -- out of
// memory, a lost device, a driver error -- throws gpu::VulkanFailure (the call, its result, file and line), which
// the public entry points (Device::create, Renderer's methods) catch and return as a visbuf::Error: exceptions
// never leave the library, and nothing in it aborts on a VkResult. User-facing failures (bad input, no device) are
// returned as visbuf::Result where they are found, as before.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>

#include "visbuf/core/result.h"

namespace visbuf::gpu {

struct VulkanFailure {
  const char* call;  // the checked expression, as written
  VkResult result;
  const char* file;
  int line;
};

const char* resultName(VkResult result);
// The error a host sees: OutOfMemory, DeviceLost or VulkanError, with the call, result name, file and line.
Error errorOf(const VulkanFailure& failure);
[[noreturn]] void vkCheckFailed(const char* call, VkResult result, const char* file, int line);

namespace testing {
// Fault injection for tests: the `after`-th VK_CHECK from now (0: the next one) fails with `result` instead of making
// its call, as a call that failed would; disarm() cancels it. Thread-safe; one atomic load per check while disarmed.
void failCheck(uint32_t after, VkResult result);
void disarm();
}  // namespace testing

namespace detail {
// True (and `result` set) where the injected failure replaces this check's call.
bool injectedFailure(VkResult& result);
}  // namespace detail

}  // namespace visbuf::gpu

#define VK_CHECK(call)                                                               \
  do {                                                                               \
    VkResult vkCheckResult_;                                                         \
    if (!::visbuf::gpu::detail::injectedFailure(vkCheckResult_)) vkCheckResult_ = (call); \
    if (vkCheckResult_ != VK_SUCCESS)                                                \
      ::visbuf::gpu::vkCheckFailed(#call, vkCheckResult_, __FILE__, __LINE__);       \
  } while (0)

// A wait for submitted work (fence, queue): a failed wait first drains `queue` (its result ignored), so that the
// unwinding that follows may destroy what the submitted commands use.
#define VK_CHECK_WAIT(call, queue)                                                   \
  do {                                                                               \
    VkResult vkCheckResult_;                                                         \
    if (!::visbuf::gpu::detail::injectedFailure(vkCheckResult_)) vkCheckResult_ = (call); \
    if (vkCheckResult_ != VK_SUCCESS) {                                              \
      vkQueueWaitIdle(queue);                                                        \
      ::visbuf::gpu::vkCheckFailed(#call, vkCheckResult_, __FILE__, __LINE__);       \
    }                                                                                \
  } while (0)

namespace visbuf::gpu {
// Runs f (returning a Result or a Status); a VulkanFailure thrown inside comes back as its error. The public entry
// points of the library wrap their bodies in it.
template <class F>
auto catchVulkan(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const VulkanFailure& failure) {
    return errorOf(failure);
  }
}
}  // namespace visbuf::gpu
