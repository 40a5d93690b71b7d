// The view host's window system, instance, device and frame objects (the swapchain and presentation:
// view_swapchain.cpp).
#include "view_host.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <fmt/format.h>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include "cli_checks.h"
#include "view_vk.h"

namespace visbuf::tools {

namespace view_vk {

std::string resultText(VkResult r) {
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

Error error(const char* what, VkResult r) {
  return {ErrorCode::NoDevice, fmt::format("{} failed: {}", what, resultText(r))};
}

bool optimalFeatures(VkPhysicalDevice pd, VkFormat format, VkFormatFeatureFlags want) {
  VkFormatProperties props{};
  vkGetPhysicalDeviceFormatProperties(pd, format, &props);
  return (props.optimalTilingFeatures & want) == want;
}

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

}  // namespace view_vk

namespace {

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

const char* deviceTypeName(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
  }
}

}  // namespace

using view_vk::isSrgb;
using view_vk::optimalFeatures;

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
