// The view host's swapchain and presentation: the surface format (sRGB, a UNORM surface with an sRGB twin image,
// or linear), the swapchain and its per-image semaphores, the upload and intermediate images, and each frame's
// blit of the renderer's colour output to the screen (view_host.h).
#include "view_host.h"

#include <algorithm>
#include <cstring>
#include <optional>

#include <fmt/format.h>
#include <glm/gtc/packing.hpp>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include "view_vk.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::tools {

using gpu::imageBarrier;
using view_vk::isSrgb;
using view_vk::optimalFeatures;
using view_vk::srgbTwin;

void ViewHost::destroySwapchainObjects(bool keepSwapchain) {
  for (VkSemaphore s : presentReady_) vkDestroySemaphore(device_, s, nullptr);
  presentReady_.clear();
  for (Slot& s : slots_) {
    if (s.intermediate) vkDestroyImage(device_, s.intermediate, nullptr);
    if (s.intermediateMemory) vkFreeMemory(device_, s.intermediateMemory, nullptr);
    s.intermediate = VK_NULL_HANDLE;
    s.intermediateMemory = VK_NULL_HANDLE;
  }
  images_.clear();
  if (!keepSwapchain && swapchain_) {
    vkDestroySwapchainKHR(device_, swapchain_, nullptr);
    swapchain_ = VK_NULL_HANDLE;
  }
}

Status ViewHost::recreateSwapchain() {
  vkDeviceWaitIdle(device_);
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  VkSurfaceCapabilitiesKHR caps{};
  VIEW_TRY(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(physical_, surface_, &caps));
  VkExtent2D extent = caps.currentExtent;
  if (extent.width == UINT32_MAX) {
    extent.width = std::clamp(uint32_t(std::max(fw, 0)), caps.minImageExtent.width, caps.maxImageExtent.width);
    extent.height = std::clamp(uint32_t(std::max(fh, 0)), caps.minImageExtent.height, caps.maxImageExtent.height);
  }
  destroySwapchainObjects(true);
  VkSwapchainKHR old = swapchain_;
  swapchain_ = VK_NULL_HANDLE;
  extent_ = {0, 0};
  if (extent.width == 0 || extent.height == 0) {  // minimised: no swapchain until the window has a size
    if (old) vkDestroySwapchainKHR(device_, old, nullptr);
    return {};
  }
  if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT))
    return makeError(ErrorCode::NoDevice, "the window surface's images cannot be transfer destinations (blits)");

  uint32_t formatCount = 0;
  VIEW_TRY(vkGetPhysicalDeviceSurfaceFormatsKHR(physical_, surface_, &formatCount, nullptr));
  std::vector<VkSurfaceFormatKHR> formats(formatCount);
  VIEW_TRY(vkGetPhysicalDeviceSurfaceFormatsKHR(physical_, surface_, &formatCount, formats.data()));
  if (formats.empty()) return makeError(ErrorCode::NoDevice, "the window surface offers no formats");
  // sRGB where offered (the blit encodes); else a UNORM format with an sRGB twin (blit to the twin, copy the
  // bytes); else the first format, shown linear.
  const VkFormatFeatureFlags blitDst = VK_FORMAT_FEATURE_BLIT_DST_BIT;
  std::optional<VkSurfaceFormatKHR> pick;
  VkFormat twin = VK_FORMAT_UNDEFINED;
  if (!unormSurface_)
    for (const VkSurfaceFormatKHR& f : formats)
      if (!pick && isSrgb(f.format) && f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR &&
          optimalFeatures(physical_, f.format, blitDst))
        pick = f;
  for (const VkSurfaceFormatKHR& f : formats) {
    const VkFormat t = srgbTwin(f.format);
    if (!pick && t != VK_FORMAT_UNDEFINED && f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR &&
        optimalFeatures(physical_, t, blitDst | VK_FORMAT_FEATURE_TRANSFER_SRC_BIT)) {
      pick = f;
      twin = t;
    }
  }
  if (!pick) {
    for (const VkSurfaceFormatKHR& f : formats)
      if (!pick && optimalFeatures(physical_, f.format, blitDst)) pick = f;
    if (!pick) return makeError(ErrorCode::NoDevice, "no surface format of the window can be a blit destination");
  }
  surfaceFormat_ = *pick;
  intermediateFormat_ = twin;

  uint32_t modeCount = 0;
  VIEW_TRY(vkGetPhysicalDeviceSurfacePresentModesKHR(physical_, surface_, &modeCount, nullptr));
  std::vector<VkPresentModeKHR> modes(modeCount);
  VIEW_TRY(vkGetPhysicalDeviceSurfacePresentModesKHR(physical_, surface_, &modeCount, modes.data()));
  presentMode_ = VK_PRESENT_MODE_FIFO_KHR;  // always offered
  if (mailbox_ && std::find(modes.begin(), modes.end(), VK_PRESENT_MODE_MAILBOX_KHR) != modes.end())
    presentMode_ = VK_PRESENT_MODE_MAILBOX_KHR;

  uint32_t imageCount = std::max(caps.minImageCount + 1, 3u);
  if (caps.maxImageCount > 0) imageCount = std::min(imageCount, caps.maxImageCount);
  VkSwapchainCreateInfoKHR sci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  sci.surface = surface_;
  sci.minImageCount = imageCount;
  sci.imageFormat = surfaceFormat_.format;
  sci.imageColorSpace = surfaceFormat_.colorSpace;
  sci.imageExtent = extent;
  sci.imageArrayLayers = 1;
  sci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  sci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  sci.preTransform = caps.currentTransform;
  sci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  if (!(caps.supportedCompositeAlpha & VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR))
    for (VkCompositeAlphaFlagBitsKHR a : {VK_COMPOSITE_ALPHA_INHERIT_BIT_KHR, VK_COMPOSITE_ALPHA_PRE_MULTIPLIED_BIT_KHR,
                                          VK_COMPOSITE_ALPHA_POST_MULTIPLIED_BIT_KHR})
      if (caps.supportedCompositeAlpha & a) {
        sci.compositeAlpha = a;
        break;
      }
  sci.presentMode = presentMode_;
  sci.clipped = VK_TRUE;
  sci.oldSwapchain = old;
  const VkResult r = vkCreateSwapchainKHR(device_, &sci, nullptr, &swapchain_);
  if (old) vkDestroySwapchainKHR(device_, old, nullptr);
  if (r != VK_SUCCESS) {
    swapchain_ = VK_NULL_HANDLE;
    return view_vk::error("vkCreateSwapchainKHR", r);
  }
  extent_ = extent;
  uint32_t count = 0;
  VIEW_TRY(vkGetSwapchainImagesKHR(device_, swapchain_, &count, nullptr));
  images_.resize(count);
  VIEW_TRY(vkGetSwapchainImagesKHR(device_, swapchain_, &count, images_.data()));
  presentReady_.resize(count, VK_NULL_HANDLE);
  for (VkSemaphore& s : presentReady_) {
    VkSemaphoreCreateInfo sci2{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    VIEW_TRY(vkCreateSemaphore(device_, &sci2, nullptr, &s));
  }
  return createIntermediates();
}

Status ViewHost::createIntermediates() {
  if (intermediateFormat_ == VK_FORMAT_UNDEFINED) return {};
  for (Slot& s : slots_) {
    VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ici.imageType = VK_IMAGE_TYPE_2D;
    ici.format = intermediateFormat_;
    ici.extent = {extent_.width, extent_.height, 1};
    ici.mipLevels = 1;
    ici.arrayLayers = 1;
    ici.samples = VK_SAMPLE_COUNT_1_BIT;
    ici.tiling = VK_IMAGE_TILING_OPTIMAL;
    ici.usage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    ici.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    VIEW_TRY(vkCreateImage(device_, &ici, nullptr, &s.intermediate));
    VkMemoryRequirements req{};
    vkGetImageMemoryRequirements(device_, s.intermediate, &req);
    uint32_t type = UINT32_MAX;
    for (uint32_t i = 0; i < memory_.memoryTypeCount && type == UINT32_MAX; ++i)
      if ((req.memoryTypeBits & (1u << i)) &&
          (memory_.memoryTypes[i].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT))
        type = i;
    for (uint32_t i = 0; i < memory_.memoryTypeCount && type == UINT32_MAX; ++i)
      if (req.memoryTypeBits & (1u << i)) type = i;
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = req.size;
    mai.memoryTypeIndex = type;
    VIEW_TRY(vkAllocateMemory(device_, &mai, nullptr, &s.intermediateMemory));
    VIEW_TRY(vkBindImageMemory(device_, s.intermediate, s.intermediateMemory, 0));
  }
  return {};
}

uint32_t ViewHost::memoryType(uint32_t typeBits, VkMemoryPropertyFlags want) const {
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i)
    if ((typeBits & (1u << i)) && (memory_.memoryTypes[i].propertyFlags & want) == want) return i;
  return UINT32_MAX;
}

void ViewHost::destroyUpload(Slot& s) {
  if (s.upload) vkDestroyBuffer(device_, s.upload, nullptr);
  if (s.uploadMemory) vkFreeMemory(device_, s.uploadMemory, nullptr);
  if (s.uploadImage) vkDestroyImage(device_, s.uploadImage, nullptr);
  if (s.uploadImageMemory) vkFreeMemory(device_, s.uploadImageMemory, nullptr);
  s.upload = VK_NULL_HANDLE;
  s.uploadMemory = VK_NULL_HANDLE;
  s.uploadMapped = nullptr;
  s.uploadImage = VK_NULL_HANDLE;
  s.uploadImageMemory = VK_NULL_HANDLE;
  s.uploadWidth = s.uploadHeight = 0;
}

Result<ViewHost::Presented> ViewHost::presentPixels(uint32_t slot, const std::vector<float>& rgba, uint32_t width,
                                                    uint32_t height) {
  if (rgba.size() != size_t(width) * height * 4)
    return makeError(ErrorCode::InvalidArgument, "presentPixels: the image is not width x height RGBA");
  Slot& s = slots_[slot];  // beginFrame waited for this slot's last frame: its upload objects are free
  if (s.uploadWidth != width || s.uploadHeight != height) {
    destroyUpload(s);
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = VkDeviceSize(rgba.size()) * sizeof(float);
    bci.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
    VIEW_TRY(vkCreateBuffer(device_, &bci, nullptr, &s.upload));
    VkMemoryRequirements req{};
    vkGetBufferMemoryRequirements(device_, s.upload, &req);
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = req.size;
    mai.memoryTypeIndex =
        memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    if (mai.memoryTypeIndex == UINT32_MAX) return makeError(ErrorCode::NoDevice, "no host-visible memory for a view");
    VIEW_TRY(vkAllocateMemory(device_, &mai, nullptr, &s.uploadMemory));
    VIEW_TRY(vkBindBufferMemory(device_, s.upload, s.uploadMemory, 0));
    VIEW_TRY(vkMapMemory(device_, s.uploadMemory, 0, VK_WHOLE_SIZE, 0, &s.uploadMapped));
    VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ici.imageType = VK_IMAGE_TYPE_2D;
    ici.format = VK_FORMAT_R32G32B32A32_SFLOAT;
    ici.extent = {width, height, 1};
    ici.mipLevels = ici.arrayLayers = 1;
    ici.samples = VK_SAMPLE_COUNT_1_BIT;
    ici.tiling = VK_IMAGE_TILING_OPTIMAL;
    ici.usage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    VIEW_TRY(vkCreateImage(device_, &ici, nullptr, &s.uploadImage));
    vkGetImageMemoryRequirements(device_, s.uploadImage, &req);
    mai.allocationSize = req.size;
    mai.memoryTypeIndex = memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (mai.memoryTypeIndex == UINT32_MAX) mai.memoryTypeIndex = memoryType(req.memoryTypeBits, 0);
    VIEW_TRY(vkAllocateMemory(device_, &mai, nullptr, &s.uploadImageMemory));
    VIEW_TRY(vkBindImageMemory(device_, s.uploadImage, s.uploadImageMemory, 0));
    s.uploadWidth = width;
    s.uploadHeight = height;
  }
  std::memcpy(s.uploadMapped, rgba.data(), rgba.size() * sizeof(float));
  RecordedFrame frame;
  frame.color = {s.uploadImage, VK_NULL_HANDLE, VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL};
  frame.width = width;
  frame.height = height;
  return submitAndPresent(slot, frame, false);
}

Result<bool> ViewHost::beginFrame(uint32_t slot) {
  Slot& s = slots_[slot];
  VIEW_TRY(vkWaitForFences(device_, 1, &s.fence, VK_TRUE, UINT64_MAX));
  if (!swapchain_) return false;
  const VkResult r = vkAcquireNextImageKHR(device_, swapchain_, UINT64_MAX, s.acquired, VK_NULL_HANDLE, &imageIndex_);
  if (r == VK_ERROR_OUT_OF_DATE_KHR) return false;
  if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR) return view_vk::error("vkAcquireNextImageKHR", r);
  return true;  // suboptimal: the acquire signalled the semaphore; present reports it and the swapchain is rebuilt
}

Result<ViewHost::Presented> ViewHost::submitAndPresent(uint32_t slot, const RecordedFrame& frame, bool readback) {
  Slot& s = slots_[slot];
  const VkImage target = images_[imageIndex_];
  const VkPipelineStageFlags2 transfer = VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT;
  if (readback) {
    const VkDeviceSize size = VkDeviceSize(frame.width) * frame.height * 8;  // rgba16f
    if (size != readbackSize_) {
      if (readback_) vkDestroyBuffer(device_, readback_, nullptr);
      if (readbackMemory_) vkFreeMemory(device_, readbackMemory_, nullptr);
      readback_ = VK_NULL_HANDLE;
      readbackMemory_ = VK_NULL_HANDLE;
      readbackSize_ = 0;
      VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
      bci.size = size;
      bci.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
      bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
      VIEW_TRY(vkCreateBuffer(device_, &bci, nullptr, &readback_));
      VkMemoryRequirements req{};
      vkGetBufferMemoryRequirements(device_, readback_, &req);
      const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
      uint32_t type = UINT32_MAX;
      for (uint32_t i = 0; i < memory_.memoryTypeCount && type == UINT32_MAX; ++i)
        if ((req.memoryTypeBits & (1u << i)) && (memory_.memoryTypes[i].propertyFlags & want) == want) type = i;
      if (type == UINT32_MAX) return makeError(ErrorCode::NoDevice, "no host-visible coherent memory for the screenshot");
      VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
      mai.allocationSize = req.size;
      mai.memoryTypeIndex = type;
      VIEW_TRY(vkAllocateMemory(device_, &mai, nullptr, &readbackMemory_));
      VIEW_TRY(vkBindBufferMemory(device_, readback_, readbackMemory_, 0));
      readbackSize_ = size;
    }
    readbackWidth_ = frame.width;
    readbackHeight_ = frame.height;
  }

  VIEW_TRY(vkResetCommandBuffer(s.cmd, 0));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VIEW_TRY(vkBeginCommandBuffer(s.cmd, &bi));
  // The renderer's last command buffer made the colour output visible to every later command in
  // frame.color.layout; the swapchain image's transition waits on the acquire semaphore (same stage).
  imageBarrier(s.cmd, target, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, transfer, 0, transfer,
               VK_ACCESS_2_TRANSFER_WRITE_BIT);
  if (s.uploadImage && frame.color.image == s.uploadImage) {  // presentPixels: the staged pixels into the image
    imageBarrier(s.cmd, s.uploadImage, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, transfer, 0,
                 transfer, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {frame.width, frame.height, 1};
    vkCmdCopyBufferToImage(s.cmd, s.upload, s.uploadImage, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
    imageBarrier(s.cmd, s.uploadImage, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                 transfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, transfer, VK_ACCESS_2_TRANSFER_READ_BIT);
  }
  const VkImage blitTarget = s.intermediate ? s.intermediate : target;
  if (s.intermediate)
    imageBarrier(s.cmd, s.intermediate, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, transfer, 0,
                 transfer, VK_ACCESS_2_TRANSFER_WRITE_BIT);
  VkImageBlit blit{};
  blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  blit.srcOffsets[1] = {int32_t(frame.width), int32_t(frame.height), 1};
  blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  blit.dstOffsets[1] = {int32_t(extent_.width), int32_t(extent_.height), 1};
  // Same size (always, but for the frame a resize lands on): nearest is exact. Else linear where supported.
  const bool sameSize = frame.width == extent_.width && frame.height == extent_.height;
  const VkFilter filter = !sameSize && optimalFeatures(physical_, frame.color.format,
                                                       VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT)
                              ? VK_FILTER_LINEAR
                              : VK_FILTER_NEAREST;
  vkCmdBlitImage(s.cmd, frame.color.image, frame.color.layout, blitTarget, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                 &blit, filter);
  if (s.intermediate) {
    imageBarrier(s.cmd, s.intermediate, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                 transfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, transfer, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkImageCopy copy{};
    copy.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.extent = {extent_.width, extent_.height, 1};
    vkCmdCopyImage(s.cmd, s.intermediate, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target,
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
  }
  if (readback) {
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {frame.width, frame.height, 1};
    vkCmdCopyImageToBuffer(s.cmd, frame.color.image, frame.color.layout, readback_, 1, &region);
    VkBufferMemoryBarrier2 b{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER_2};
    b.srcStageMask = transfer;
    b.srcAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT;
    b.dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT;
    b.dstAccessMask = VK_ACCESS_2_HOST_READ_BIT;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.buffer = readback_;
    b.size = VK_WHOLE_SIZE;
    VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dep.bufferMemoryBarrierCount = 1;
    dep.pBufferMemoryBarriers = &b;
    vkCmdPipelineBarrier2(s.cmd, &dep);
  }
  // Present waits on the semaphore signalled after every command of the submit: no destination stage.
  imageBarrier(s.cmd, target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, transfer,
               VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_NONE, 0);
  VIEW_TRY(vkEndCommandBuffer(s.cmd));

  std::vector<VkCommandBufferSubmitInfo> cmds;
  for (VkCommandBuffer c : frame.commandBuffers) cmds.push_back({VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO, nullptr, c, 0});
  cmds.push_back({VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO, nullptr, s.cmd, 0});
  VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  wait.semaphore = s.acquired;
  wait.stageMask = transfer;
  VkSemaphoreSubmitInfo signal{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  signal.semaphore = presentReady_[imageIndex_];
  signal.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  VkSubmitInfo2 submit{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  submit.waitSemaphoreInfoCount = 1;
  submit.pWaitSemaphoreInfos = &wait;
  submit.commandBufferInfoCount = uint32_t(cmds.size());
  submit.pCommandBufferInfos = cmds.data();
  submit.signalSemaphoreInfoCount = 1;
  submit.pSignalSemaphoreInfos = &signal;
  VIEW_TRY(vkResetFences(device_, 1, &s.fence));
  VIEW_TRY(vkQueueSubmit2(queue_, 1, &submit, s.fence));

  VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  pi.waitSemaphoreCount = 1;
  pi.pWaitSemaphores = &presentReady_[imageIndex_];
  pi.swapchainCount = 1;
  pi.pSwapchains = &swapchain_;
  pi.pImageIndices = &imageIndex_;
  const VkResult r = vkQueuePresentKHR(queue_, &pi);
  if (r == VK_SUCCESS) return Presented{true, false};
  if (r == VK_SUBOPTIMAL_KHR) return Presented{true, true};
  if (r == VK_ERROR_OUT_OF_DATE_KHR) return Presented{false, true};
  return view_vk::error("vkQueuePresentKHR", r);
}

Result<std::vector<float>> ViewHost::readColor(uint32_t& width, uint32_t& height) {
  if (!readback_) return makeError(ErrorCode::InvalidArgument, "no frame was read back");
  vkDeviceWaitIdle(device_);
  void* mapped = nullptr;
  VIEW_TRY(vkMapMemory(device_, readbackMemory_, 0, readbackSize_, 0, &mapped));
  width = readbackWidth_;
  height = readbackHeight_;
  const size_t n = size_t(width) * height * 4;
  std::vector<float> rgba(n);
  const uint16_t* half = static_cast<const uint16_t*>(mapped);
  for (size_t i = 0; i < n; ++i) rgba[i] = glm::unpackHalf1x16(half[i]);
  vkUnmapMemory(device_, readbackMemory_);
  return rgba;
}

}  // namespace visbuf::tools
