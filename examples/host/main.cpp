// A host engine using visbuf as a module: it owns its Vulkan instance/device/queue and hands them in.
// (A host without its own device can call visbuf::gpu::Device::create instead.)
#include <cstdio>
#include <vector>

#include <vulkan/vulkan.h>

#include <visbuf/gpu/device.h>
#include <visbuf/render/renderer.h>
#include <visbuf/scene/generate.h>

namespace {
struct HostVulkan {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t family = 0;
  ~HostVulkan() {
    if (device) vkDestroyDevice(device, nullptr);
    if (instance) vkDestroyInstance(instance, nullptr);
  }
};

bool createHostVulkan(HostVulkan& h) {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.apiVersion = VK_API_VERSION_1_3;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  if (vkCreateInstance(&ici, nullptr, &h.instance) != VK_SUCCESS) return false;
  uint32_t n = 1;
  vkEnumeratePhysicalDevices(h.instance, &n, &h.physical);
  if (n == 0) return false;
  uint32_t fc = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(h.physical, &fc, nullptr);
  std::vector<VkQueueFamilyProperties> fams(fc);
  vkGetPhysicalDeviceQueueFamilyProperties(h.physical, &fc, fams.data());
  for (uint32_t i = 0; i < fc; ++i)
    if ((fams[i].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) == (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) {
      h.family = i;
      break;
    }
  // The features visbuf requires (gpu::Device::requiredFeaturesText()).
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  f13.dynamicRendering = VK_TRUE;
  f13.synchronization2 = VK_TRUE;
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  f12.drawIndirectCount = VK_TRUE;
  f12.pNext = &f13;
  VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
  f11.shaderDrawParameters = VK_TRUE;
  f11.pNext = &f12;
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  f2.features.multiDrawIndirect = f2.features.drawIndirectFirstInstance = VK_TRUE;
  f2.features.geometryShader = f2.features.fragmentStoresAndAtomics = VK_TRUE;
  f2.pNext = &f11;
  float prio = 1.0f;
  VkDeviceQueueCreateInfo q{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  q.queueFamilyIndex = h.family;
  q.queueCount = 1;
  q.pQueuePriorities = &prio;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &f2;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &q;
  if (vkCreateDevice(h.physical, &dci, nullptr, &h.device) != VK_SUCCESS) return false;
  vkGetDeviceQueue(h.device, h.family, 0, &h.queue);
  return true;
}
}  // namespace

int main() {
  HostVulkan host;
  if (!createHostVulkan(host)) {
    std::fprintf(stderr, "host: no Vulkan 1.3 device\n");
    return 1;
  }
  auto device = visbuf::gpu::Device::adopt({host.instance, host.physical, host.device, host.queue, host.family});
  if (!device) {
    std::fprintf(stderr, "host: %s\n", device.error().message.c_str());
    return 1;
  }
  auto scene = visbuf::makeFieldScene({.objects = 1000});
  if (!scene) return 1;
  {
    auto renderer = visbuf::Renderer::create(**device, *scene, {.width = 320, .height = 240});
    if (!renderer) {
      std::fprintf(stderr, "host: %s\n", renderer.error().message.c_str());
      return 1;
    }
    auto frame = (*renderer)->renderFrame(scene->defaultCamera, {});
    if (!frame) return 1;
    std::printf("host: rendered %ux%u, %u objects drawn, %llu triangles, %.2f ms GPU\n", frame->width, frame->height,
                frame->stats.drawsRendered, (unsigned long long)frame->stats.trianglesDrawn, frame->stats.gpuMs);
  }
  device->reset();  // visbuf releases its objects before the host destroys the device
  return 0;
}
