#include "visbuf/gpu/check.h"

#include <fmt/format.h>

#include <atomic>

namespace visbuf::gpu {

const char* resultName(VkResult result) {
  switch (result) {
#define VB_CASE(x) \
  case x: return #x;
    VB_CASE(VK_SUCCESS)
    VB_CASE(VK_NOT_READY)
    VB_CASE(VK_TIMEOUT)
    VB_CASE(VK_INCOMPLETE)
    VB_CASE(VK_ERROR_OUT_OF_HOST_MEMORY)
    VB_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    VB_CASE(VK_ERROR_INITIALIZATION_FAILED)
    VB_CASE(VK_ERROR_DEVICE_LOST)
    VB_CASE(VK_ERROR_MEMORY_MAP_FAILED)
    VB_CASE(VK_ERROR_LAYER_NOT_PRESENT)
    VB_CASE(VK_ERROR_EXTENSION_NOT_PRESENT)
    VB_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
    VB_CASE(VK_ERROR_INCOMPATIBLE_DRIVER)
    VB_CASE(VK_ERROR_TOO_MANY_OBJECTS)
    VB_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED)
    VB_CASE(VK_ERROR_FRAGMENTED_POOL)
    VB_CASE(VK_ERROR_OUT_OF_POOL_MEMORY)
#undef VB_CASE
    default: return "VK_ERROR_<unknown>";
  }
}

Error errorOf(const VulkanFailure& f) {
  const ErrorCode code = f.result == VK_ERROR_OUT_OF_HOST_MEMORY || f.result == VK_ERROR_OUT_OF_DEVICE_MEMORY ||
                                 f.result == VK_ERROR_OUT_OF_POOL_MEMORY
                             ? ErrorCode::OutOfMemory
                         : f.result == VK_ERROR_DEVICE_LOST ? ErrorCode::DeviceLost
                                                            : ErrorCode::VulkanError;
  return makeError(code, fmt::format("{} returned {} ({}) at {}:{}", f.call, resultName(f.result),
                                     static_cast<int>(f.result), f.file, f.line));
}

void vkCheckFailed(const char* call, VkResult result, const char* file, int line) {
  throw VulkanFailure{call, result, file, line};
}

namespace {
// Checks left before the injected failure (-1: none armed), and the result it reports.
std::atomic<int64_t> checksBeforeFailure{-1};
std::atomic<VkResult> injectedResult{VK_SUCCESS};
}  // namespace

namespace testing {
void failCheck(uint32_t after, VkResult result) {
  injectedResult.store(result);
  checksBeforeFailure.store(after);
}
void disarm() { checksBeforeFailure.store(-1); }
}  // namespace testing

namespace detail {
bool injectedFailure(VkResult& result) {
  if (checksBeforeFailure.load(std::memory_order_relaxed) < 0) return false;
  if (checksBeforeFailure.fetch_sub(1) != 0) return false;
  result = injectedResult.load();
  return true;
}
}  // namespace detail

}  // namespace visbuf::gpu
