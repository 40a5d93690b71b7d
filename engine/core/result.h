// Result<T>: a value or a user-facing error (code + actionable message).
// Engine code returns these across module boundaries instead of throwing.
#pragma once

#include <string>
#include <utility>
#include <variant>

namespace visbuf {

enum class ErrorCode {
  InvalidArgument,  // impossible option or parameter combination
  FileNotFound,
  MalformedInput,   // a file that parses but whose contents are invalid (NaN, bad counts, ...)
  Unsupported,      // valid input we do not handle (yet)
  NoDevice,         // no Vulkan device satisfies our requirements
  VulkanError,      // a Vulkan call failed (other than the two below)
  CapacityExceeded,
  IoError,
  OutOfMemory,      // host or device memory ran out (VK_ERROR_OUT_OF_HOST/DEVICE_MEMORY, a failed allocation)
  DeviceLost,       // VK_ERROR_DEVICE_LOST: the device (and every renderer on it) must be re-created
};

const char* errorCodeName(ErrorCode code);

struct Error {
  ErrorCode code;
  std::string message;
};

template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : data_(std::move(value)) {}  // NOLINT: implicit by design
  Result(Error error) : data_(std::move(error)) {}  // NOLINT

  bool ok() const { return std::holds_alternative<T>(data_); }
  explicit operator bool() const { return ok(); }
  T& value() & { return std::get<T>(data_); }
  const T& value() const& { return std::get<T>(data_); }
  T&& value() && { return std::get<T>(std::move(data_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const Error& error() const { return std::get<Error>(data_); }

 private:
  std::variant<T, Error> data_;
};

// Result<void> equivalent.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error)), failed_(true) {}  // NOLINT
  bool ok() const { return !failed_; }
  explicit operator bool() const { return ok(); }
  const Error& error() const { return error_; }

 private:
  Error error_{ErrorCode::InvalidArgument, {}};
  bool failed_ = false;
};

inline Error makeError(ErrorCode code, std::string message) { return Error{code, std::move(message)}; }

}  // namespace visbuf
