// Move-only owners of buffers and images (one allocation each: the frame uses a handful of large
// resources, so a sub-allocator would buy nothing yet), plus staging upload and readback.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <vulkan/vulkan.h>

#include "visbuf/gpu/device.h"

namespace visbuf::gpu {

enum class MemoryUse { DeviceLocal, HostVisible };

class Buffer {
 public:
  Buffer() = default;
  Buffer(Device& device, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use);
  ~Buffer() { reset(); }
  Buffer(Buffer&& o) noexcept { *this = std::move(o); }
  Buffer& operator=(Buffer&& o) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  void reset();
  VkBuffer handle() const { return buffer_; }
  VkDeviceSize size() const { return size_; }
  void* mapped() const { return mapped_; }  // non-null for MemoryUse::HostVisible
  // Buffer device address (created with VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT), else 0.
  VkDeviceAddress address() const { return address_; }
  explicit operator bool() const { return buffer_ != VK_NULL_HANDLE; }

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkDeviceSize size_ = 0;
  void* mapped_ = nullptr;
  VkDeviceAddress address_ = 0;
};

// A typed view of a buffer range (a uniform texel buffer): lavapipe fetches texels as whole vector loads, where its
// storage-buffer reads cost a bounds-checked scalar load per lane and word.
class BufferView {
 public:
  BufferView() = default;
  BufferView(Device& device, const Buffer& buffer, VkFormat format, VkDeviceSize offset, VkDeviceSize range);
  ~BufferView() { reset(); }
  BufferView(BufferView&& o) noexcept { *this = std::move(o); }
  BufferView& operator=(BufferView&& o) noexcept;
  BufferView(const BufferView&) = delete;
  BufferView& operator=(const BufferView&) = delete;

  void reset();
  VkBufferView handle() const { return view_; }
  explicit operator bool() const { return view_ != VK_NULL_HANDLE; }

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  VkBufferView view_ = VK_NULL_HANDLE;
};

class Image {
 public:
  Image() = default;
  Image(Device& device, VkFormat format, uint32_t width, uint32_t height, VkImageUsageFlags usage,
        VkImageAspectFlags aspect, uint32_t mipLevels = 1, uint32_t arrayLayers = 0,
        VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT);
  ~Image() { reset(); }
  Image(Image&& o) noexcept { *this = std::move(o); }
  Image& operator=(Image&& o) noexcept;
  Image(const Image&) = delete;
  Image& operator=(const Image&) = delete;

  void reset();
  VkImage handle() const { return image_; }
  VkImageView view() const { return view_; }
  VkFormat format() const { return format_; }
  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }
  uint32_t mipLevels() const { return mipLevels_; }
  uint32_t layers() const { return layers_; }  // array layers (its view is a 2D array view when created with > 0)
  VkImageAspectFlags aspect() const { return aspect_; }
  VkSampleCountFlagBits samples() const { return samples_; }
  // A view of one mip level; the caller owns it (vkDestroyImageView).
  VkImageView createLevelView(uint32_t level) const;
  explicit operator bool() const { return image_ != VK_NULL_HANDLE; }

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  VkImage image_ = VK_NULL_HANDLE;
  VkImageView view_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  uint32_t width_ = 0, height_ = 0;
  uint32_t mipLevels_ = 1;
  uint32_t layers_ = 1;
  VkImageAspectFlags aspect_ = 0;
  VkSampleCountFlagBits samples_ = VK_SAMPLE_COUNT_1_BIT;
};

// Creates a device-local buffer holding `bytes` (size rounded up to 4, at least 16 bytes) via staging.
Buffer uploadBuffer(Device& device, const void* data, size_t bytes, VkBufferUsageFlags usage);

template <typename T>
Buffer uploadVector(Device& device, const std::vector<T>& v, VkBufferUsageFlags usage) {
  return uploadBuffer(device, v.data(), v.size() * sizeof(T), usage);
}

// Copies `bytes` from `offset` of a buffer (created with VK_BUFFER_USAGE_TRANSFER_SRC_BIT) back to the host,
// waiting for the copy (one-shot submission: for tests and tools, never inside a frame).
std::vector<uint8_t> downloadBuffer(Device& device, const Buffer& buffer, VkDeviceSize offset, VkDeviceSize bytes);

// Image layout transition (synchronization2) of a single-level, single-layer colour image that is not a
// gpu::Image (a host's own image, a swapchain image).
void imageBarrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to,
                  VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                  VkAccessFlags2 dstAccess);
// Image layout transition (synchronization2), whole image (every level and layer).
void imageBarrier(VkCommandBuffer cmd, const Image& image, VkImageLayout from, VkImageLayout to,
                  VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                  VkAccessFlags2 dstAccess);
void memoryBarrier(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                   VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess);

// Bytes per texel for the formats we read back.
uint32_t formatBytes(VkFormat format);

}  // namespace visbuf::gpu
