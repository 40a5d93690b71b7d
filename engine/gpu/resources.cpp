#include "visbuf/gpu/resources.h"

#include <algorithm>
#include <cstring>
#include <utility>

#include "visbuf/gpu/check.h"

namespace visbuf::gpu {

namespace {
// One allocation for one resource; device-local memory falls back to any type (lavapipe has no
// separate device memory). Failure to find a type is fatal like any Vulkan allocation failure.
VkDeviceMemory allocate(Device& device, const VkMemoryRequirements& req, MemoryUse use, bool deviceAddress) {
  VkMemoryPropertyFlags flags = use == MemoryUse::HostVisible
                                    ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
                                    : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  uint32_t type = device.findMemoryType(req.memoryTypeBits, flags);
  if (type == UINT32_MAX && use == MemoryUse::DeviceLocal) type = device.findMemoryType(req.memoryTypeBits, 0);
  if (type == UINT32_MAX) vkCheckFailed("findMemoryType", VK_ERROR_OUT_OF_DEVICE_MEMORY, __FILE__, __LINE__);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = type;
  VkMemoryAllocateFlagsInfo flagsInfo{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
  flagsInfo.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  if (deviceAddress) ai.pNext = &flagsInfo;
  VkDeviceMemory memory;
  VK_CHECK(vkAllocateMemory(device.device(), &ai, nullptr, &memory));
  return memory;
}
}  // namespace

Buffer::Buffer(Device& device, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use)
    : device_(device.device()), size_(size) {
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = size;
  bci.usage = usage;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VK_CHECK(vkCreateBuffer(device_, &bci, nullptr, &buffer_));
  try {  // (a failure below releases what was made: no destructor runs for an object whose constructor threw)
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device_, buffer_, &req);
    const bool deviceAddress = (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) != 0;
    memory_ = allocate(device, req, use, deviceAddress);
    VK_CHECK(vkBindBufferMemory(device_, buffer_, memory_, 0));
    if (deviceAddress) {
      VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
      info.buffer = buffer_;
      address_ = vkGetBufferDeviceAddress(device_, &info);
    }
    if (use == MemoryUse::HostVisible) VK_CHECK(vkMapMemory(device_, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_));
  } catch (...) {
    reset();
    throw;
  }
}

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    reset();
    device_ = std::exchange(o.device_, VK_NULL_HANDLE);
    buffer_ = std::exchange(o.buffer_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    size_ = std::exchange(o.size_, 0);
    mapped_ = std::exchange(o.mapped_, nullptr);
    address_ = std::exchange(o.address_, 0);
  }
  return *this;
}

void Buffer::reset() {
  if (buffer_) vkDestroyBuffer(device_, buffer_, nullptr);
  if (memory_) vkFreeMemory(device_, memory_, nullptr);
  buffer_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
  address_ = 0;
  size_ = 0;
}

BufferView::BufferView(Device& device, const Buffer& buffer, VkFormat format, VkDeviceSize offset,
                       VkDeviceSize range)
    : device_(device.device()) {
  VkBufferViewCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
  ci.buffer = buffer.handle();
  ci.format = format;
  ci.offset = offset;
  ci.range = range;
  VK_CHECK(vkCreateBufferView(device_, &ci, nullptr, &view_));
}

BufferView& BufferView::operator=(BufferView&& o) noexcept {
  if (this != &o) {
    reset();
    device_ = std::exchange(o.device_, VK_NULL_HANDLE);
    view_ = std::exchange(o.view_, VK_NULL_HANDLE);
  }
  return *this;
}

void BufferView::reset() {
  if (view_) vkDestroyBufferView(device_, view_, nullptr);
  view_ = VK_NULL_HANDLE;
}

Image::Image(Device& device, VkFormat format, uint32_t width, uint32_t height, VkImageUsageFlags usage,
             VkImageAspectFlags aspect, uint32_t mipLevels, uint32_t arrayLayers, VkSampleCountFlagBits samples)
    : device_(device.device()),
      format_(format),
      width_(width),
      height_(height),
      mipLevels_(mipLevels),
      layers_(std::max(arrayLayers, 1u)),
      aspect_(aspect),
      samples_(samples) {
  VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ici.imageType = VK_IMAGE_TYPE_2D;
  ici.format = format;
  ici.extent = {width, height, 1};
  ici.mipLevels = mipLevels;
  ici.arrayLayers = layers_;
  ici.samples = samples;
  ici.tiling = VK_IMAGE_TILING_OPTIMAL;
  ici.usage = usage;
  ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  VK_CHECK(vkCreateImage(device_, &ici, nullptr, &image_));
  try {  // (as Buffer's)
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(device_, image_, &req);
    memory_ = allocate(device, req, MemoryUse::DeviceLocal, false);
    VK_CHECK(vkBindImageMemory(device_, image_, memory_, 0));
    VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vci.image = image_;
    vci.viewType = arrayLayers > 0 ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D;
    vci.format = format;
    vci.subresourceRange = {aspect, 0, mipLevels, 0, layers_};
    VK_CHECK(vkCreateImageView(device_, &vci, nullptr, &view_));
  } catch (...) {
    reset();
    throw;
  }
}

VkImageView Image::createLevelView(uint32_t level) const {
  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = image_;
  vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vci.format = format_;
  vci.subresourceRange = {aspect_, level, 1, 0, 1};
  VkImageView view;
  VK_CHECK(vkCreateImageView(device_, &vci, nullptr, &view));
  return view;
}

Image& Image::operator=(Image&& o) noexcept {
  if (this != &o) {
    reset();
    device_ = std::exchange(o.device_, VK_NULL_HANDLE);
    image_ = std::exchange(o.image_, VK_NULL_HANDLE);
    view_ = std::exchange(o.view_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    format_ = o.format_;
    width_ = o.width_;
    height_ = o.height_;
    mipLevels_ = o.mipLevels_;
    layers_ = o.layers_;
    aspect_ = o.aspect_;
    samples_ = o.samples_;
  }
  return *this;
}

void Image::reset() {
  if (view_) vkDestroyImageView(device_, view_, nullptr);
  if (image_) vkDestroyImage(device_, image_, nullptr);
  if (memory_) vkFreeMemory(device_, memory_, nullptr);
  view_ = VK_NULL_HANDLE;
  image_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
}

Buffer uploadBuffer(Device& device, const void* data, size_t bytes, VkBufferUsageFlags usage) {
  size_t size = (bytes + 3) & ~size_t(3);
  if (size < 16) size = 16;
  Buffer staging(device, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::HostVisible);
  std::memset(staging.mapped(), 0, size);
  if (bytes) std::memcpy(staging.mapped(), data, bytes);
  Buffer buffer(device, size, usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::DeviceLocal);
  VkCommandBuffer cmd = device.beginOneShot();
  VkBufferCopy region{0, 0, size};
  vkCmdCopyBuffer(cmd, staging.handle(), buffer.handle(), 1, &region);
  device.submitOneShot(cmd);
  return buffer;
}

std::vector<uint8_t> downloadBuffer(Device& device, const Buffer& buffer, VkDeviceSize offset, VkDeviceSize bytes) {
  std::vector<uint8_t> out(bytes);
  if (bytes == 0) return out;
  Buffer staging(device, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::HostVisible);
  VkCommandBuffer cmd = device.beginOneShot();
  VkBufferCopy region{offset, 0, bytes};
  vkCmdCopyBuffer(cmd, buffer.handle(), staging.handle(), 1, &region);
  device.submitOneShot(cmd);
  std::memcpy(out.data(), staging.mapped(), bytes);
  return out;
}

namespace {
void layoutBarrier(VkCommandBuffer cmd, VkImage image, const VkImageSubresourceRange& range, VkImageLayout from,
                   VkImageLayout to, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                   VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = srcStage;
  b.srcAccessMask = srcAccess;
  b.dstStageMask = dstStage;
  b.dstAccessMask = dstAccess;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = range;
  VkDependencyInfo di{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  di.imageMemoryBarrierCount = 1;
  di.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &di);
}
}  // namespace

void imageBarrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to,
                  VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                  VkAccessFlags2 dstAccess) {
  layoutBarrier(cmd, image, {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}, from, to, srcStage, srcAccess, dstStage,
                dstAccess);
}

void imageBarrier(VkCommandBuffer cmd, const Image& image, VkImageLayout from, VkImageLayout to,
                  VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                  VkAccessFlags2 dstAccess) {
  layoutBarrier(cmd, image.handle(), {image.aspect(), 0, image.mipLevels(), 0, image.layers()}, from, to, srcStage,
                srcAccess, dstStage, dstAccess);
}

void memoryBarrier(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                   VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess) {
  VkMemoryBarrier2 b{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
  b.srcStageMask = srcStage;
  b.srcAccessMask = srcAccess;
  b.dstStageMask = dstStage;
  b.dstAccessMask = dstAccess;
  VkDependencyInfo di{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  di.memoryBarrierCount = 1;
  di.pMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &di);
}

uint32_t formatBytes(VkFormat format) {
  switch (format) {
    case VK_FORMAT_R32_UINT: return 4;
    case VK_FORMAT_R32G32_UINT: return 8;
    case VK_FORMAT_R16G16B16A16_SFLOAT: return 8;
    case VK_FORMAT_R32G32B32A32_SFLOAT: return 16;
    case VK_FORMAT_D32_SFLOAT: return 4;
    case VK_FORMAT_R8_UNORM: return 1;
    case VK_FORMAT_R8G8B8A8_UNORM: return 4;
    case VK_FORMAT_R8G8B8A8_SRGB: return 4;
    case VK_FORMAT_R16G16_SNORM: return 4;
    case VK_FORMAT_R16G16_SFLOAT: return 4;
    case VK_FORMAT_B10G11R11_UFLOAT_PACK32: return 4;
    default: return 0;
  }
}

}  // namespace visbuf::gpu
