// Headless Vulkan 1.3 device: creation with explained selection, or adoption of a host's device.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "visbuf/core/result.h"

namespace visbuf::gpu {

enum class DevicePreference { Auto, Cpu, Gpu, Index };

struct DeviceOptions {
  DevicePreference preference = DevicePreference::Auto;  // auto: a real GPU if one qualifies, else lavapipe
  uint32_t index = 0;                                    // with DevicePreference::Index
  bool validation = false;  // VK_LAYER_KHRONOS_validation; every message is counted (see validationMessages)
  bool verbose = true;      // print the selection and rejection reasons to stderr
};

// Parses "auto", "cpu", "gpu" or a device index.
Result<DeviceOptions> parseDeviceOption(const std::string& text, DeviceOptions base = {});

// The Vulkan 1.1-1.3 feature chain visbuf needs (requiredFeaturesText()), for a host that creates its own device:
// query a physical device into it (vkGetPhysicalDeviceFeatures2(pd, &chain.f2)) and read missing(), or call
// requireAll() and chain f2 into VkDeviceCreateInfo::pNext. Not copyable (the chain points into itself).
struct RequiredFeatures {
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  RequiredFeatures() {
    f2.pNext = &f11;
    f11.pNext = &f12;
    f12.pNext = &f13;
  }
  RequiredFeatures(const RequiredFeatures&) = delete;
  RequiredFeatures& operator=(const RequiredFeatures&) = delete;
  void requireAll();                     // sets every required feature (and nothing else)
  std::vector<std::string> missing() const;  // the required features this chain does not have, by name
};

// What a host engine hands in when it owns the Vulkan objects. The device must have been created
// with the features listed by requiredFeaturesText() and a queue supporting graphics + compute.
struct ExternalDevice {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physicalDevice = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t queueFamily = 0;
  bool textureCompressionBC = false;  // the host enabled VkPhysicalDeviceFeatures::textureCompressionBC
};

class Device {
 public:
  // Creates instance + device. Errors name every physical device and why it was rejected.
  static Result<std::unique_ptr<Device>> create(const DeviceOptions& options);
  // Wraps a host's device; nothing is destroyed by this object.
  static Result<std::unique_ptr<Device>> adopt(const ExternalDevice& external);
  static const char* requiredFeaturesText();
  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physicalDevice() const { return physical_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  uint32_t queueFamily() const { return queueFamily_; }
  const VkPhysicalDeviceProperties& properties() const { return properties_; }
  const std::string& name() const { return name_; }
  bool isCpu() const { return properties_.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU; }
  // Nanoseconds per timestamp tick.
  double timestampPeriodNs() const { return properties_.limits.timestampPeriod; }
  const std::string& selectionReport() const { return selectionReport_; }
  // BC1-BC7 formats can be sampled (the optional feature, enabled when the device has it).
  bool textureCompressionBC() const { return textureCompressionBC_; }

  // Number of validation messages (warning or error severity) seen since creation. Tests require 0.
  uint32_t validationMessages() const { return validationMessages_.load(); }
  bool validationEnabled() const { return messenger_ != VK_NULL_HANDLE; }

  uint32_t findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required) const;

  // One-shot command buffer: record, submit, wait. For uploads and tests.
  VkCommandBuffer beginOneShot();
  void submitOneShot(VkCommandBuffer cmd);
  VkCommandPool commandPool() const { return pool_; }

 private:
  Device() = default;
  Status finishInit();
  static VKAPI_ATTR VkBool32 VKAPI_CALL debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                      VkDebugUtilsMessageTypeFlagsEXT types,
                                                      const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                      void* user);

  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queueFamily_ = 0;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  std::string name_;
  std::string selectionReport_;
  bool owned_ = true;
  bool textureCompressionBC_ = false;
  std::atomic<uint32_t> validationMessages_{0};
};

}  // namespace visbuf::gpu
