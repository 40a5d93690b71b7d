// The Vulkan host of `visbuf view`, built like any engine that embeds visbuf: a GLFW window, its own instance
// (validation with a counting messenger on request), a physical device that can present to the window, a
// device with VK_KHR_swapchain plus the features visbuf requires (handed to visbuf through
// gpu::Device::adopt), the swapchain, and per-frame fences, semaphores and command buffers that blit the
// renderer's colour output to the screen.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "visbuf/core/result.h"
#include "visbuf/gpu/device.h"
#include "visbuf/render/renderer.h"

struct GLFWwindow;

namespace visbuf::tools {

// Why no window can be opened ("" when one can): no DISPLAY / WAYLAND_DISPLAY, glfwInit failing, or GLFW
// finding no Vulkan loader. On success GLFW is initialised until closeWindowSystem().
std::string openWindowSystem();
void closeWindowSystem();

struct ViewHostOptions {
  uint32_t width = 1280, height = 720;  // window size (screen coordinates)
  std::string title = "visbuf view";
  bool resizable = true;
  bool validation = false;     // VK_LAYER_KHRONOS_validation + a messenger counting warnings and errors
  gpu::DeviceOptions device;   // preference (auto | cpu | gpu | index) among the devices that can present
  bool mailbox = false;        // VK_PRESENT_MODE_MAILBOX_KHR where offered, else FIFO
  bool unormSurface = false;   // pick a UNORM surface format even when an sRGB one is offered
  uint32_t framesInFlight = 2;
};

class ViewHost {
 public:
  // Needs openWindowSystem() to have succeeded.
  static Result<std::unique_ptr<ViewHost>> create(const ViewHostOptions& options);
  ~ViewHost();
  ViewHost(const ViewHost&) = delete;
  ViewHost& operator=(const ViewHost&) = delete;

  GLFWwindow* window() const { return window_; }
  gpu::ExternalDevice external() const;
  const std::string& deviceName() const { return deviceName_; }
  // Warning and error messages of the validation layer so far (0 without validation).
  uint32_t validationMessages() const { return validationMessages_.load(); }
  VkExtent2D extent() const { return extent_; }
  VkSurfaceFormatKHR surfaceFormat() const { return surfaceFormat_; }
  // How the linear colour output reaches the surface format (for the start-up line).
  std::string presentDescription() const;

  // The window's framebuffer size differs from the swapchain's extent.
  bool resized() const;
  // Waits for the device to go idle, then builds the swapchain for the window's current framebuffer size.
  // A zero-sized (minimised) window leaves extent() at 0x0 and no swapchain.
  Status recreateSwapchain();

  // Frame slot `slot` (frame index % framesInFlight): waits for that slot's fence (the frame framesInFlight
  // earlier has finished), then acquires a swapchain image. Returns false when the swapchain is out of date
  // (nothing was acquired; recreate it and try again).
  Result<bool> beginFrame(uint32_t slot);
  // Submits the renderer's command buffers followed by this slot's blit to the acquired image (waiting on the
  // acquire semaphore, signalling the image's present semaphore and the slot's fence), then presents. With
  // readback, the same command buffer also copies the colour output into a host-visible buffer (readColor).
  struct Presented {
    bool presented = false;  // the present engine took the image
    bool recreate = false;   // the swapchain is out of date or suboptimal: recreate it before the next frame
  };
  Result<Presented> submitAndPresent(uint32_t slot, const RecordedFrame& frame, bool readback);
  // Presents a CPU image instead of a rendered frame (the debug views: RGBA float, linear, top row first,
  // width x height): copied into the slot's own upload image, then blitted like a frame's colour output. Needs
  // beginFrame(slot) first, as submitAndPresent.
  Result<Presented> presentPixels(uint32_t slot, const std::vector<float>& rgba, uint32_t width, uint32_t height);
  // The colour output copied by the last submitAndPresent with readback, as RGBA float (linear, top row
  // first); waits for the device to go idle first.
  Result<std::vector<float>> readColor(uint32_t& width, uint32_t& height);
  void waitIdle();

 private:
  ViewHost() = default;
  Status createInstance(const ViewHostOptions& options);
  Status pickDevice(const ViewHostOptions& options);
  Status createDevice();
  Status createFrameObjects();
  void destroySwapchainObjects(bool keepSwapchain);
  Status createIntermediates();
  static VKAPI_ATTR VkBool32 VKAPI_CALL debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                      VkDebugUtilsMessageTypeFlagsEXT types,
                                                      const VkDebugUtilsMessengerCallbackDataEXT* data, void* user);

  struct Slot {
    VkFence fence = VK_NULL_HANDLE;
    VkSemaphore acquired = VK_NULL_HANDLE;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    // UNORM surfaces: the blit writes this sRGB image (the blit encodes), then its bytes are copied to the
    // swapchain image unchanged.
    VkImage intermediate = VK_NULL_HANDLE;
    VkDeviceMemory intermediateMemory = VK_NULL_HANDLE;
    // presentPixels: a host-visible staging buffer and an RGBA32F image of the pixels' size.
    VkBuffer upload = VK_NULL_HANDLE;
    VkDeviceMemory uploadMemory = VK_NULL_HANDLE;
    void* uploadMapped = nullptr;
    VkImage uploadImage = VK_NULL_HANDLE;
    VkDeviceMemory uploadImageMemory = VK_NULL_HANDLE;
    uint32_t uploadWidth = 0, uploadHeight = 0;
  };
  void destroyUpload(Slot& s);
  uint32_t memoryType(uint32_t typeBits, VkMemoryPropertyFlags want) const;  // UINT32_MAX: none

  GLFWwindow* window_ = nullptr;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties memory_{};
  uint32_t family_ = 0;
  bool textureCompressionBC_ = false;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  std::string deviceName_;
  bool mailbox_ = false;
  bool unormSurface_ = false;
  std::atomic<uint32_t> validationMessages_{0};

  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkSurfaceFormatKHR surfaceFormat_{};
  VkFormat intermediateFormat_ = VK_FORMAT_UNDEFINED;  // UNDEFINED: blit straight into the swapchain image
  VkPresentModeKHR presentMode_ = VK_PRESENT_MODE_FIFO_KHR;
  VkExtent2D extent_{0, 0};
  std::vector<VkImage> images_;
  // One per swapchain image: the present engine may still hold the semaphore of an image when the frame slot
  // that signalled it comes around again, but not once that image has been acquired again.
  std::vector<VkSemaphore> presentReady_;
  std::vector<Slot> slots_;
  uint32_t imageIndex_ = 0;  // acquired by the last beginFrame

  VkBuffer readback_ = VK_NULL_HANDLE;
  VkDeviceMemory readbackMemory_ = VK_NULL_HANDLE;
  VkDeviceSize readbackSize_ = 0;
  uint32_t readbackWidth_ = 0, readbackHeight_ = 0;
};

}  // namespace visbuf::tools
