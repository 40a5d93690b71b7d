// VK_CHECK: every Vulkan call that must succeed is checked in every build (release included).
// A failure here is a programming error or a lost device, not bad user input: it prints the call,
// file, line and result name, then aborts. User-facing failures are returned as visbuf::Result.
#pragma once

#include <vulkan/vulkan.h>

namespace visbuf::gpu {

const char* resultName(VkResult result);
[[noreturn]] void vkCheckFailed(const char* call, VkResult result, const char* file, int line);

}  // namespace visbuf::gpu

#define VK_CHECK(call)                                                      \
  do {                                                                      \
    VkResult vkCheckResult_ = (call);                                       \
    if (vkCheckResult_ != VK_SUCCESS)                                       \
      ::visbuf::gpu::vkCheckFailed(#call, vkCheckResult_, __FILE__, __LINE__); \
  } while (0)
