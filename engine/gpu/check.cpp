#include "visbuf/gpu/check.h"

#include <cstdio>
#include <cstdlib>

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

void vkCheckFailed(const char* call, VkResult result, const char* file, int line) {
  std::fprintf(stderr, "visbuf: fatal: %s returned %s (%d) at %s:%d\n", call, resultName(result),
               static_cast<int>(result), file, line);
  std::fflush(stderr);
  std::abort();
}

}  // namespace visbuf::gpu
