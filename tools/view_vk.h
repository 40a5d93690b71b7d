// Vulkan helpers shared by the view host's files (view_host.cpp: instance and device; view_swapchain.cpp: the
// swapchain and presentation). Internal to `visbuf view`.
#pragma once

#include <string>

#include <vulkan/vulkan.h>

#include "visbuf/core/result.h"

namespace visbuf::tools::view_vk {

std::string resultText(VkResult r);
// ErrorCode::NoDevice: "<what> failed: <result>".
Error error(const char* what, VkResult r);
// Whether the device supports every feature of `want` for optimally tiled images of `format`.
bool optimalFeatures(VkPhysicalDevice pd, VkFormat format, VkFormatFeatureFlags want);
// The sRGB format with the same bytes as a UNORM surface format (UNDEFINED: none).
VkFormat srgbTwin(VkFormat format);
bool isSrgb(VkFormat format);

}  // namespace visbuf::tools::view_vk

// Returns view_vk::error(<the call>, result) from the enclosing function where the call does not succeed.
#define VIEW_TRY(call)                                                        \
  do {                                                                        \
    const VkResult viewResult_ = (call);                                      \
    if (viewResult_ != VK_SUCCESS) return view_vk::error(#call, viewResult_); \
  } while (0)
