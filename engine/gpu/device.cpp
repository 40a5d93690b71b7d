#include "visbuf/gpu/device.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <fmt/format.h>

#include "visbuf/core/log.h"
#include "visbuf/gpu/check.h"

namespace visbuf::gpu {

namespace {

const char* typeName(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
  }
}

// Returns the list of missing requirements (empty = suitable).
std::vector<std::string> missingRequirements(VkPhysicalDevice pd, uint32_t* queueFamilyOut) {
  std::vector<std::string> missing;
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(pd, &props);
  if (props.apiVersion < VK_API_VERSION_1_3)
    missing.push_back(fmt::format("Vulkan {}.{} < 1.3", VK_API_VERSION_MAJOR(props.apiVersion),
                                  VK_API_VERSION_MINOR(props.apiVersion)));
  RequiredFeatures fc;
  vkGetPhysicalDeviceFeatures2(pd, &fc.f2);
  for (const std::string& m : fc.missing()) missing.push_back("no " + m);
  if (props.limits.timestampPeriod <= 0.0f) missing.push_back("no timestamps");

  uint32_t count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, nullptr);
  std::vector<VkQueueFamilyProperties> families(count);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, families.data());
  bool found = false;
  for (uint32_t i = 0; i < count; ++i) {
    const VkQueueFlags want = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
    if ((families[i].queueFlags & want) == want && families[i].timestampValidBits > 0) {
      *queueFamilyOut = i;
      found = true;
      break;
    }
  }
  if (!found) missing.push_back("no graphics+compute queue with timestamps");
  return missing;
}

bool hasLayer(const char* name) {
  uint32_t count = 0;
  vkEnumerateInstanceLayerProperties(&count, nullptr);
  std::vector<VkLayerProperties> layers(count);
  vkEnumerateInstanceLayerProperties(&count, layers.data());
  for (auto& l : layers)
    if (std::strcmp(l.layerName, name) == 0) return true;
  return false;
}

}  // namespace

Result<DeviceOptions> parseDeviceOption(const std::string& text, DeviceOptions base) {
  if (text == "auto") {
    base.preference = DevicePreference::Auto;
  } else if (text == "cpu") {
    base.preference = DevicePreference::Cpu;
  } else if (text == "gpu") {
    base.preference = DevicePreference::Gpu;
  } else {
    char* end = nullptr;
    unsigned long v = std::strtoul(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || v > 64)
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("--device '{}': expected auto, cpu, gpu or a device index", text));
    base.preference = DevicePreference::Index;
    base.index = static_cast<uint32_t>(v);
  }
  return base;
}

void RequiredFeatures::requireAll() {
  f2.features.multiDrawIndirect = VK_TRUE;
  f2.features.drawIndirectFirstInstance = VK_TRUE;
  f2.features.geometryShader = VK_TRUE;
  f2.features.fragmentStoresAndAtomics = VK_TRUE;
  f2.features.shaderInt64 = VK_TRUE;
  f11.shaderDrawParameters = VK_TRUE;
  f12.drawIndirectCount = VK_TRUE;
  f12.shaderBufferInt64Atomics = VK_TRUE;  // sw_raster.comp: atomicMax of (depth << 32 | payload)
  f12.bufferDeviceAddress = VK_TRUE;  // skinned vertices (MeshData.skinnedVertex*), object-record scatter
  f13.dynamicRendering = VK_TRUE;
  f13.synchronization2 = VK_TRUE;
}

std::vector<std::string> RequiredFeatures::missing() const {
  std::vector<std::string> out;
  auto need = [&](VkBool32 have, const char* name) {
    if (!have) out.push_back(name);
  };
  need(f2.features.multiDrawIndirect, "multiDrawIndirect");
  need(f2.features.drawIndirectFirstInstance, "drawIndirectFirstInstance");
  need(f2.features.geometryShader, "geometryShader (gl_PrimitiveID in fragment shaders)");
  need(f2.features.fragmentStoresAndAtomics, "fragmentStoresAndAtomics");
  need(f11.shaderDrawParameters, "shaderDrawParameters");
  need(f12.drawIndirectCount, "drawIndirectCount");
  need(f12.bufferDeviceAddress, "bufferDeviceAddress");
  need(f2.features.shaderInt64, "shaderInt64");
  need(f12.shaderBufferInt64Atomics, "shaderBufferInt64Atomics (the software micro-raster's depth + ID atomics)");
  need(f13.dynamicRendering, "dynamicRendering");
  need(f13.synchronization2, "synchronization2");
  return out;
}

const char* Device::requiredFeaturesText() {
  return "Vulkan 1.3 with multiDrawIndirect, drawIndirectFirstInstance, geometryShader, "
         "fragmentStoresAndAtomics, shaderDrawParameters, drawIndirectCount, bufferDeviceAddress, dynamicRendering, "
         "synchronization2, shaderInt64, shaderBufferInt64Atomics";
}

VKAPI_ATTR VkBool32 VKAPI_CALL Device::debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                     VkDebugUtilsMessageTypeFlagsEXT,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                     void* user) {
  if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    auto* self = static_cast<Device*>(user);
    self->validationMessages_.fetch_add(1);
    logMessage(severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT ? LogLevel::Error : LogLevel::Warning,
               std::string("validation: ") + (data->pMessage ? data->pMessage : "(null)"));
  }
  return VK_FALSE;
}

Result<std::unique_ptr<Device>> Device::create(const DeviceOptions& options) {
  return gpu::catchVulkan([&]() -> Result<std::unique_ptr<Device>> {
    std::unique_ptr<Device> dev(new Device());

    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "visbuf";
    app.pEngineName = "visbuf";
    app.apiVersion = VK_API_VERSION_1_3;

    std::vector<const char*> layers;
    std::vector<const char*> extensions;
    const bool validation = options.validation;
    if (validation) {
      if (!hasLayer("VK_LAYER_KHRONOS_validation"))
        return makeError(ErrorCode::NoDevice,
                         "validation requested but VK_LAYER_KHRONOS_validation is not installed "
                         "(apt-get install vulkan-validationlayers)");
      layers.push_back("VK_LAYER_KHRONOS_validation");
      extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    }
    VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ici.pApplicationInfo = &app;
    ici.enabledLayerCount = static_cast<uint32_t>(layers.size());
    ici.ppEnabledLayerNames = layers.data();
    ici.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
    ici.ppEnabledExtensionNames = extensions.data();
    VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                      VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    mci.pfnUserCallback = &Device::debugCallback;
    mci.pUserData = dev.get();
    if (validation) ici.pNext = &mci;  // also catches messages during instance creation
    VkResult r = vkCreateInstance(&ici, nullptr, &dev->instance_);
    if (r != VK_SUCCESS)
      return makeError(ErrorCode::NoDevice,
                       fmt::format("vkCreateInstance failed ({}): is a Vulkan 1.3 driver installed "
                                   "(apt-get install mesa-vulkan-drivers libvulkan1)?",
                                   resultName(r)));
    if (validation) {
      auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(dev->instance_, "vkCreateDebugUtilsMessengerEXT"));
      VK_CHECK(create(dev->instance_, &mci, nullptr, &dev->messenger_));
    }

    uint32_t count = 0;
    VK_CHECK(vkEnumeratePhysicalDevices(dev->instance_, &count, nullptr));
    std::vector<VkPhysicalDevice> devices(count);
    VK_CHECK(vkEnumeratePhysicalDevices(dev->instance_, &count, devices.data()));

    std::string report;
    int chosen = -1;
    int chosenScore = -1;
    uint32_t chosenFamily = 0;
    for (uint32_t i = 0; i < count; ++i) {
      VkPhysicalDeviceProperties props;
      vkGetPhysicalDeviceProperties(devices[i], &props);
      uint32_t family = 0;
      std::vector<std::string> why = missingRequirements(devices[i], &family);
      const bool isCpu = props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
      switch (options.preference) {
        case DevicePreference::Cpu:
          if (!isCpu) why.push_back("not a CPU device (--device cpu)");
          break;
        case DevicePreference::Gpu:
          if (isCpu) why.push_back("a CPU device (--device gpu)");
          break;
        case DevicePreference::Index:
          if (i != options.index) why.push_back(fmt::format("not device {} (--device {})", options.index, options.index));
          break;
        case DevicePreference::Auto: break;
      }
      int score = props.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU     ? 3
                  : props.deviceType == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU ? 2
                  : isCpu                                                      ? 0
                                                                               : 1;
      std::string line = fmt::format("  [{}] {} ({})", i, props.deviceName, typeName(props.deviceType));
      if (why.empty()) {
        line += ": suitable";
        if (score > chosenScore) {
          chosen = static_cast<int>(i);
          chosenScore = score;
          chosenFamily = family;
        }
      } else {
        line += ": rejected: ";
        for (size_t k = 0; k < why.size(); ++k) line += (k ? "; " : "") + why[k];
      }
      report += line + "\n";
    }
    if (chosen < 0)
      return makeError(ErrorCode::NoDevice, "no Vulkan device is suitable:\n" + report +
                                                "visbuf needs " + requiredFeaturesText());

    dev->physical_ = devices[static_cast<size_t>(chosen)];
    dev->queueFamily_ = chosenFamily;
    vkGetPhysicalDeviceProperties(dev->physical_, &dev->properties_);
    report = fmt::format("device: [{}] {} (auto prefers a GPU over a CPU device)\n", chosen,
                         dev->properties_.deviceName) +
             report;
    dev->selectionReport_ = report;
    if (options.verbose) logMessage(LogLevel::Info, report.substr(0, report.find_last_not_of('\n') + 1));

    RequiredFeatures fc;  // enable exactly what we require
    fc.requireAll();
    // Optional: block-compressed textures are sampled as such where the device has BC formats; elsewhere the
    // texture upload decompresses them to RGBA8 (scene/gpu_textures.cpp).
    {
      VkPhysicalDeviceFeatures have{};
      vkGetPhysicalDeviceFeatures(dev->physical_, &have);
      fc.f2.features.textureCompressionBC = have.textureCompressionBC;
      dev->textureCompressionBC_ = have.textureCompressionBC == VK_TRUE;
    }
    float priority = 1.0f;
    VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qci.queueFamilyIndex = dev->queueFamily_;
    qci.queueCount = 1;
    qci.pQueuePriorities = &priority;
    VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    dci.pNext = &fc.f2;
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    r = vkCreateDevice(dev->physical_, &dci, nullptr, &dev->device_);
    if (r != VK_SUCCESS)
      return makeError(ErrorCode::NoDevice, fmt::format("vkCreateDevice failed on {}: {}",
                                                        dev->properties_.deviceName, resultName(r)));
    vkGetDeviceQueue(dev->device_, dev->queueFamily_, 0, &dev->queue_);
    Status s = dev->finishInit();
    if (!s) return s.error();
    return dev;
  });
}

Result<std::unique_ptr<Device>> Device::adopt(const ExternalDevice& external) {
  return gpu::catchVulkan([&]() -> Result<std::unique_ptr<Device>> {
    if (!external.instance || !external.physicalDevice || !external.device || !external.queue)
      return makeError(ErrorCode::InvalidArgument, "ExternalDevice: instance, physicalDevice, device and queue are required");
    std::unique_ptr<Device> dev(new Device());
    dev->owned_ = false;
    dev->instance_ = external.instance;
    dev->physical_ = external.physicalDevice;
    dev->device_ = external.device;
    dev->queue_ = external.queue;
    dev->queueFamily_ = external.queueFamily;
    dev->textureCompressionBC_ = external.textureCompressionBC;
    uint32_t family = 0;
    std::vector<std::string> why = missingRequirements(external.physicalDevice, &family);
    if (!why.empty()) {
      std::string msg = "the host's device lacks:";
      for (auto& w : why) msg += " " + w + ";";
      return makeError(ErrorCode::NoDevice, msg + " (features must also be enabled at device creation)");
    }
    vkGetPhysicalDeviceProperties(dev->physical_, &dev->properties_);
    dev->selectionReport_ = fmt::format("device: {} (provided by host)\n", dev->properties_.deviceName);
    Status s = dev->finishInit();
    if (!s) return s.error();
    return dev;
  });
}

Status Device::finishInit() {
  name_ = properties_.deviceName;
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = queueFamily_;
  VK_CHECK(vkCreateCommandPool(device_, &pci, nullptr, &pool_));
  return {};
}

Device::~Device() {
  if (device_) vkDeviceWaitIdle(device_);
  if (pool_) vkDestroyCommandPool(device_, pool_, nullptr);
  if (!owned_) return;
  if (device_) vkDestroyDevice(device_, nullptr);
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    destroy(instance_, messenger_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
}

uint32_t Device::findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required) const {
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i)
    if ((typeBits & (1u << i)) && (memory_.memoryTypes[i].propertyFlags & required) == required) return i;
  return UINT32_MAX;
}

VkCommandBuffer Device::beginOneShot() {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = pool_;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd;
  VK_CHECK(vkAllocateCommandBuffers(device_, &ai, &cmd));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VK_CHECK(vkBeginCommandBuffer(cmd, &bi));
  return cmd;
}

void Device::submitOneShot(VkCommandBuffer cmd) {
  VK_CHECK(vkEndCommandBuffer(cmd));
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  VK_CHECK(vkQueueSubmit(queue_, 1, &si, VK_NULL_HANDLE));
  VK_CHECK_WAIT(vkQueueWaitIdle(queue_), queue_);
  vkFreeCommandBuffers(device_, pool_, 1, &cmd);
}

}  // namespace visbuf::gpu
