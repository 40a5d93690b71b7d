#include "view_host.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>

#include <fmt/format.h>
#include <glm/gtc/packing.hpp>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include "cli_checks.h"
#include "visbuf/gpu/resources.h"

namespace visbuf::tools {

namespace {

std::string vkResultText(VkResult r) {
  switch (r) {
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_SURFACE_LOST_KHR: return "VK_ERROR_SURFACE_LOST_KHR";
    case VK_ERROR_NATIVE_WINDOW_IN_USE_KHR: return "VK_ERROR_NATIVE_WINDOW_IN_USE_KHR";
    case VK_ERROR_OUT_OF_DATE_KHR: return "VK_ERROR_OUT_OF_DATE_KHR";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    default: return fmt::format("VkResult {}", int(r));
  }
}

Error vkError(const char* what, VkResult r) {
  return {ErrorCode::NoDevice, fmt::format("{} failed: {}", what, vkResultText(r))};
}

#define VIEW_TRY(call)                                                     \
  do {                                                                     \
    const VkResult viewResult_ = (call);                                   \
    if (viewResult_ != VK_SUCCESS) return vkError(#call, viewResult_);     \
  } while (0)

bool hasLayer(const char* name) {
  uint32_t count = 0;
  vkEnumerateInstanceLayerProperties(&count, nullptr);
  std::vector<VkLayerProperties> layers(count);
  vkEnumerateInstanceLayerProperties(&count, layers.data());
  for (const VkLayerProperties& l : layers)
    if (std::strcmp(l.layerName, name) == 0) return true;
  return false;
}

bool hasDeviceExtension(VkPhysicalDevice pd, const char* name) {
  uint32_t count = 0;
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &count, nullptr);
  std::vector<VkExtensionProperties> exts(count);
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &count, exts.data());
  for (const VkExtensionProperties& e : exts)
    if (std::strcmp(e.extensionName, name) == 0) return true;
  return false;
}

bool optimalFeatures(VkPhysicalDevice pd, VkFormat format, VkFormatFeatureFlags want) {
  VkFormatProperties props{};
  vkGetPhysicalDeviceFormatProperties(pd, format, &props);
  return (props.optimalTilingFeatures & want) == want;
}

const char* deviceTypeName(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
  }
}

// The sRGB format with the same bytes as a UNORM surface format (UNDEFINED: none).
VkFormat srgbTwin(VkFormat format) {
  switch (format) {
    case VK_FORMAT_B8G8R8A8_UNORM: return VK_FORMAT_B8G8R8A8_SRGB;
    case VK_FORMAT_R8G8B8A8_UNORM: return VK_FORMAT_R8G8B8A8_SRGB;
    case VK_FORMAT_A8B8G8R8_UNORM_PACK32: return VK_FORMAT_A8B8G8R8_SRGB_PACK32;
    default: return VK_FORMAT_UNDEFINED;
  }
}

bool isSrgb(VkFormat format) {
  return format == VK_FORMAT_B8G8R8A8_SRGB || format == VK_FORMAT_R8G8B8A8_SRGB ||
         format == VK_FORMAT_A8B8G8R8_SRGB_PACK32;
}

using gpu::imageBarrier;

}  // namespace

std::string openWindowSystem() {
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((!display || !*display) && (!wayland || !*wayland)) return "DISPLAY and WAYLAND_DISPLAY are not set";
  if (glfwInit() != GLFW_TRUE) {
    const char* why = nullptr;
    glfwGetError(&why);
    return fmt::format("the window system cannot be opened: {}", why ? printable(why) : std::string("glfwInit failed"));
  }
  if (glfwVulkanSupported() != GLFW_TRUE) {
    glfwTerminate();
    return "GLFW finds no Vulkan loader";
  }
  return {};
}

void closeWindowSystem() { glfwTerminate(); }

VKAPI_ATTR VkBool32 VKAPI_CALL ViewHost::debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                       VkDebugUtilsMessageTypeFlagsEXT,
                                                       const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    static_cast<std::atomic<uint32_t>*>(user)->fetch_add(1);
    std::fprintf(stderr, "visbuf view: validation: %s\n", data && data->pMessage ? data->pMessage : "(null)");
  }
  return VK_FALSE;
}

Result<std::unique_ptr<ViewHost>> ViewHost::create(const ViewHostOptions& options) {
  std::unique_ptr<ViewHost> host(new ViewHost());
  host->mailbox_ = options.mailbox;
  host->unormSurface_ = options.unormSurface;
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_RESIZABLE, options.resizable ? GLFW_TRUE : GLFW_FALSE);
  host->window_ = glfwCreateWindow(int(options.width), int(options.height), options.title.c_str(), nullptr, nullptr);
  if (!host->window_) {
    const char* why = nullptr;
    glfwGetError(&why);
    return makeError(ErrorCode::NoDevice,
                     fmt::format("no window: {}", why ? printable(why) : std::string("glfwCreateWindow failed")));
  }
  glfwSetInputMode(host->window_, GLFW_STICKY_KEYS, GLFW_TRUE);
  glfwSetInputMode(host->window_, GLFW_STICKY_MOUSE_BUTTONS, GLFW_TRUE);
  if (Status s = host->createInstance(options); !s) return s.error();
  if (Status s = host->pickDevice(options); !s) return s.error();
  if (Status s = host->createDevice(); !s) return s.error();
  host->slots_.resize(std::clamp(options.framesInFlight, 1u, 4u));
  if (Status s = host->createFrameObjects(); !s) return s.error();
  if (Status s = host->recreateSwapchain(); !s) return s.error();
  return host;
}

Status ViewHost::createInstance(const ViewHostOptions& options) {
  uint32_t glfwCount = 0;
  const char** glfwExtensions = glfwGetRequiredInstanceExtensions(&glfwCount);
  if (!glfwExtensions) return makeError(ErrorCode::NoDevice, "GLFW names no Vulkan surface extensions for this window system");
  std::vector<const char*> extensions(glfwExtensions, glfwExtensions + glfwCount);
  std::vector<const char*> layers;
  if (options.validation) {
    if (!hasLayer("VK_LAYER_KHRONOS_validation"))
      return makeError(ErrorCode::NoDevice,
                       "--validation: VK_LAYER_KHRONOS_validation is not installed (apt-get install vulkan-validationlayers)");
    layers.push_back("VK_LAYER_KHRONOS_validation");
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "visbuf view";
  app.pEngineName = "visbuf";
  app.apiVersion = VK_API_VERSION_1_3;
  VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  mci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                    VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  mci.pfnUserCallback = &ViewHost::debugCallback;
  mci.pUserData = &validationMessages_;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  if (options.validation) ici.pNext = &mci;  // also counts messages of instance creation
  ici.pApplicationInfo = &app;
  ici.enabledLayerCount = uint32_t(layers.size());
  ici.ppEnabledLayerNames = layers.data();
  ici.enabledExtensionCount = uint32_t(extensions.size());
  ici.ppEnabledExtensionNames = extensions.data();
  VIEW_TRY(vkCreateInstance(&ici, nullptr, &instance_));
  if (options.validation) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
    if (!create) return makeError(ErrorCode::NoDevice, "vkCreateDebugUtilsMessengerEXT is missing");
    VIEW_TRY(create(instance_, &mci, nullptr, &messenger_));
  }
  VIEW_TRY(glfwCreateWindowSurface(instance_, window_, nullptr, &surface_));
  return {};
}

Status ViewHost::pickDevice(const ViewHostOptions& options) {
  uint32_t count = 0;
  VIEW_TRY(vkEnumeratePhysicalDevices(instance_, &count, nullptr));
  std::vector<VkPhysicalDevice> devices(count);
  VIEW_TRY(vkEnumeratePhysicalDevices(instance_, &count, devices.data()));
  std::string report;
  int chosen = -1, chosenScore = -1;
  uint32_t chosenFamily = 0;
  for (uint32_t i = 0; i < count; ++i) {
    VkPhysicalDevice pd = devices[i];
    VkPhysicalDeviceProperties props{};
    vkGetPhysicalDeviceProperties(pd, &props);
    std::vector<std::string> why;
    if (props.apiVersion < VK_API_VERSION_1_3) why.push_back("Vulkan < 1.3");
    gpu::RequiredFeatures fc;
    vkGetPhysicalDeviceFeatures2(pd, &fc.f2);
    for (const std::string& m : fc.missing()) why.push_back("no " + m);
    if (!hasDeviceExtension(pd, VK_KHR_SWAPCHAIN_EXTENSION_NAME)) why.push_back("no VK_KHR_swapchain");
    if (!optimalFeatures(pd, VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_FEATURE_BLIT_SRC_BIT))
      why.push_back("rgba16f cannot be a blit source");
    uint32_t familyCount = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &familyCount, nullptr);
    std::vector<VkQueueFamilyProperties> families(familyCount);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &familyCount, families.data());
    int family = -1;
    for (uint32_t f = 0; f < familyCount && family < 0; ++f) {
      const VkQueueFlags want = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
      VkBool32 present = VK_FALSE;
      vkGetPhysicalDeviceSurfaceSupportKHR(pd, f, surface_, &present);
      if ((families[f].queueFlags & want) == want && families[f].timestampValidBits > 0 && present) family = int(f);
    }
    if (family < 0) why.push_back("no graphics + compute queue with timestamps that can present to the window");
    const bool isCpu = props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
    switch (options.device.preference) {
      case gpu::DevicePreference::Cpu:
        if (!isCpu) why.push_back("not a CPU device (--device cpu)");
        break;
      case gpu::DevicePreference::Gpu:
        if (isCpu) why.push_back("a CPU device (--device gpu)");
        break;
      case gpu::DevicePreference::Index:
        if (i != options.device.index) why.push_back(fmt::format("not device {}", options.device.index));
        break;
      case gpu::DevicePreference::Auto: break;
    }
    const int score = props.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU     ? 3
                      : props.deviceType == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU ? 2
                      : isCpu                                                      ? 0
                                                                                   : 1;
    std::string line = fmt::format("  [{}] {} ({})", i, props.deviceName, deviceTypeName(props.deviceType));
    if (why.empty()) {
      line += ": suitable";
      if (score > chosenScore) {
        chosen = int(i);
        chosenScore = score;
        chosenFamily = uint32_t(family);
      }
    } else {
      line += ": rejected: ";
      for (size_t k = 0; k < why.size(); ++k) line += (k ? "; " : "") + why[k];
    }
    report += line + "\n";
  }
  if (chosen < 0)
    return makeError(ErrorCode::NoDevice, "no Vulkan device can render and present to the window:\n" + report +
                                              "visbuf needs " + gpu::Device::requiredFeaturesText() +
                                              ", plus VK_KHR_swapchain");
  physical_ = devices[size_t(chosen)];
  family_ = chosenFamily;
  VkPhysicalDeviceProperties props{};
  vkGetPhysicalDeviceProperties(physical_, &props);
  deviceName_ = props.deviceName;
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);
  std::fprintf(stderr, "device: [%d] %s (presents to the window)\n%s", chosen, printable(deviceName_).c_str(),
               report.c_str());
  return {};
}

Status ViewHost::createDevice() {
  gpu::RequiredFeatures fc;
  fc.requireAll();
  VkPhysicalDeviceFeatures have{};
  vkGetPhysicalDeviceFeatures(physical_, &have);
  fc.f2.features.textureCompressionBC = have.textureCompressionBC;  // optional: BC textures sampled as such
  textureCompressionBC_ = have.textureCompressionBC == VK_TRUE;
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = family_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  const char* extensions[] = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &fc.f2;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = 1;
  dci.ppEnabledExtensionNames = extensions;
  VIEW_TRY(vkCreateDevice(physical_, &dci, nullptr, &device_));
  vkGetDeviceQueue(device_, family_, 0, &queue_);
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = family_;
  VIEW_TRY(vkCreateCommandPool(device_, &pci, nullptr, &pool_));
  return {};
}

Status ViewHost::createFrameObjects() {
  for (Slot& s : slots_) {
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fci.flags = VK_FENCE_CREATE_SIGNALED_BIT;  // the first wait of each slot returns at once
    VIEW_TRY(vkCreateFence(device_, &fci, nullptr, &s.fence));
    VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    VIEW_TRY(vkCreateSemaphore(device_, &sci, nullptr, &s.acquired));
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool_;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    VIEW_TRY(vkAllocateCommandBuffers(device_, &ai, &s.cmd));
  }
  return {};
}

gpu::ExternalDevice ViewHost::external() const {
  gpu::ExternalDevice e;
  e.instance = instance_;
  e.physicalDevice = physical_;
  e.device = device_;
  e.queue = queue_;
  e.queueFamily = family_;
  e.textureCompressionBC = textureCompressionBC_;
  return e;
}

std::string ViewHost::presentDescription() const {
  const char* mode = presentMode_ == VK_PRESENT_MODE_MAILBOX_KHR ? "mailbox" : "fifo";
  if (intermediateFormat_ != VK_FORMAT_UNDEFINED)
    return fmt::format("UNORM surface (format {}), sRGB-encoded by a blit to an sRGB twin image, then copied; {}",
                       int(surfaceFormat_.format), mode);
  if (isSrgb(surfaceFormat_.format))
    return fmt::format("sRGB surface (format {}), encoded by the blit; {}", int(surfaceFormat_.format), mode);
  return fmt::format("surface format {} has no sRGB form: linear values are shown unencoded (too dark); {}",
                     int(surfaceFormat_.format), mode);
}

bool ViewHost::resized() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  return uint32_t(w) != extent_.width || uint32_t(h) != extent_.height;
}

void ViewHost::waitIdle() {
  if (device_) vkDeviceWaitIdle(device_);
}

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
    return vkError("vkCreateSwapchainKHR", r);
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
  if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR) return vkError("vkAcquireNextImageKHR", r);
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
  return vkError("vkQueuePresentKHR", r);
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

ViewHost::~ViewHost() {
  if (device_) {
    vkDeviceWaitIdle(device_);
    if (readback_) vkDestroyBuffer(device_, readback_, nullptr);
    if (readbackMemory_) vkFreeMemory(device_, readbackMemory_, nullptr);
    destroySwapchainObjects(false);
    for (Slot& s : slots_) {
      destroyUpload(s);
      if (s.fence) vkDestroyFence(device_, s.fence, nullptr);
      if (s.acquired) vkDestroySemaphore(device_, s.acquired, nullptr);
    }
    if (pool_) vkDestroyCommandPool(device_, pool_, nullptr);
    vkDestroyDevice(device_, nullptr);
  }
  if (surface_) vkDestroySurfaceKHR(instance_, surface_, nullptr);
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
  if (window_) glfwDestroyWindow(window_);
}

}  // namespace visbuf::tools
