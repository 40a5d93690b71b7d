#include "visbuf/core/result.h"

namespace visbuf {

const char* errorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidArgument: return "invalid argument";
    case ErrorCode::FileNotFound: return "file not found";
    case ErrorCode::MalformedInput: return "malformed input";
    case ErrorCode::Unsupported: return "unsupported";
    case ErrorCode::NoDevice: return "no suitable device";
    case ErrorCode::VulkanError: return "Vulkan error";
    case ErrorCode::CapacityExceeded: return "capacity exceeded";
    case ErrorCode::IoError: return "I/O error";
    case ErrorCode::OutOfMemory: return "out of memory";
    case ErrorCode::DeviceLost: return "device lost";
  }
  return "unknown error";
}

}  // namespace visbuf
