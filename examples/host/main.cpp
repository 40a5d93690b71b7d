// A host engine using visbuf as a module. It owns the Vulkan instance, device, queue, command buffers and fences;
// visbuf records each frame (Renderer::record) and the host submits it with its own composition commands, with up
// to --in-flight frames queued. The only waits inside the loop are on the host's fence ring. The camera orbits
// and 5 % of the objects move every frame (plus a few added, removed and hidden: visbuf::SceneMotion).
//
//   visbuf_host [--frames N] [--in-flight K] [--objects N] [--size W] [--validation] [--compare PAIRS]
//
// The host "presents" by blitting visbuf's colour output into its own RGBA8 image (where a windowed host would
// blit into a swapchain image). At the end it reads that image back and checks it against Renderer::renderFrame of
// the same camera and scene: a host that composes the frame sees what the headless path renders.
// --compare P: P interleaved pairs of the same frames recorded with the ring and rendered by renderFrame (submit
// and wait), their throughputs and the median ratio (the frames-in-flight row of docs/benchmarks.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include <visbuf/gpu/device.h>
#include <visbuf/gpu/resources.h>
#include <visbuf/render/renderer.h>
#include <visbuf/render/scene_motion.h>
#include <visbuf/scene/generate.h>

namespace {

uint32_t g_validationMessages = 0;

VKAPI_ATTR VkBool32 VKAPI_CALL onValidation(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                            VkDebugUtilsMessageTypeFlagsEXT,
                                            const VkDebugUtilsMessengerCallbackDataEXT* data, void*) {
  if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    ++g_validationMessages;
    std::fprintf(stderr, "host: validation: %s\n", data->pMessage);
  }
  return VK_FALSE;
}

#define HOST_CHECK(call)                                                      \
  do {                                                                        \
    const VkResult r_ = (call);                                               \
    if (r_ != VK_SUCCESS) {                                                   \
      std::fprintf(stderr, "host: %s failed (VkResult %d)\n", #call, int(r_)); \
      std::exit(1);                                                           \
    }                                                                         \
  } while (0)

struct HostVulkan {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t family = 0;
  ~HostVulkan() {
    if (device) vkDestroyDevice(device, nullptr);
    if (messenger) {
      auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
      if (destroy) destroy(instance, messenger, nullptr);
    }
    if (instance) vkDestroyInstance(instance, nullptr);
  }
};

bool createHostVulkan(HostVulkan& h, bool validation) {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "visbuf_host";
  app.apiVersion = VK_API_VERSION_1_3;
  const char* layer = "VK_LAYER_KHRONOS_validation";
  const char* debugExt = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  if (validation) {
    ici.enabledLayerCount = 1;
    ici.ppEnabledLayerNames = &layer;
    ici.enabledExtensionCount = 1;
    ici.ppEnabledExtensionNames = &debugExt;
  }
  if (vkCreateInstance(&ici, nullptr, &h.instance) != VK_SUCCESS) {
    std::fprintf(stderr, "host: no Vulkan 1.3 instance%s\n", validation ? " with VK_LAYER_KHRONOS_validation" : "");
    return false;
  }
  if (validation) {
    VkDebugUtilsMessengerCreateInfoEXT mi{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
    mi.pfnUserCallback = onValidation;
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(h.instance, "vkCreateDebugUtilsMessengerEXT"));
    if (!create || create(h.instance, &mi, nullptr, &h.messenger) != VK_SUCCESS) return false;
  }
  // The first device (a GPU before a CPU implementation) with every required feature and a graphics + compute
  // queue.
  uint32_t n = 0;
  vkEnumeratePhysicalDevices(h.instance, &n, nullptr);
  std::vector<VkPhysicalDevice> devices(n);
  vkEnumeratePhysicalDevices(h.instance, &n, devices.data());
  std::stable_sort(devices.begin(), devices.end(), [](VkPhysicalDevice a, VkPhysicalDevice b) {
    VkPhysicalDeviceProperties pa, pb;
    vkGetPhysicalDeviceProperties(a, &pa);
    vkGetPhysicalDeviceProperties(b, &pb);
    return (pa.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU) < (pb.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU);
  });
  for (VkPhysicalDevice pd : devices) {
    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(pd, &props);
    visbuf::gpu::RequiredFeatures have;  // what visbuf needs, queried
    vkGetPhysicalDeviceFeatures2(pd, &have.f2);
    std::string missing;
    for (const std::string& m : have.missing()) missing += (missing.empty() ? "" : ", ") + m;
    uint32_t fc = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &fc, nullptr);
    std::vector<VkQueueFamilyProperties> fams(fc);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &fc, fams.data());
    constexpr VkQueueFlags want = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
    uint32_t family = fc;
    for (uint32_t i = 0; i < fc && family == fc; ++i)
      if ((fams[i].queueFlags & want) == want && fams[i].timestampValidBits > 0) family = i;
    if (props.apiVersion < VK_API_VERSION_1_3 || !missing.empty() || family == fc) {
      std::fprintf(stderr, "host: skipping %s (%s)\n", props.deviceName,
                   !missing.empty() ? ("lacks " + missing).c_str() : "no Vulkan 1.3 or no graphics+compute queue");
      continue;
    }
    visbuf::gpu::RequiredFeatures enable;
    enable.requireAll();
    float prio = 1.0f;
    VkDeviceQueueCreateInfo q{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    q.queueFamilyIndex = family;
    q.queueCount = 1;
    q.pQueuePriorities = &prio;
    VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    dci.pNext = &enable.f2;
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &q;
    if (vkCreateDevice(pd, &dci, nullptr, &h.device) != VK_SUCCESS) continue;
    h.physical = pd;
    h.family = family;
    vkGetDeviceQueue(h.device, family, 0, &h.queue);
    std::printf("host: device %s\n", props.deviceName);
    return true;
  }
  std::fprintf(stderr, "host: no device has what visbuf needs: %s\n", visbuf::gpu::Device::requiredFeaturesText());
  return false;
}

uint32_t memoryType(VkPhysicalDevice pd, uint32_t bits, VkMemoryPropertyFlags want) {
  VkPhysicalDeviceMemoryProperties mp;
  vkGetPhysicalDeviceMemoryProperties(pd, &mp);
  for (uint32_t i = 0; i < mp.memoryTypeCount; ++i)
    if ((bits >> i & 1u) && (mp.memoryTypes[i].propertyFlags & want) == want) return i;
  std::fprintf(stderr, "host: no memory type\n");
  std::exit(1);
}

// The host's own "presentation" image (RGBA8) and a buffer to read it back at the end.
struct HostTarget {
  VkDevice device = VK_NULL_HANDLE;
  VkImage image = VK_NULL_HANDLE;
  VkDeviceMemory imageMemory = VK_NULL_HANDLE;
  VkBuffer readback = VK_NULL_HANDLE;
  VkDeviceMemory readbackMemory = VK_NULL_HANDLE;
  void* mapped = nullptr;
  ~HostTarget() {
    if (readback) vkDestroyBuffer(device, readback, nullptr);
    if (readbackMemory) vkFreeMemory(device, readbackMemory, nullptr);
    if (image) vkDestroyImage(device, image, nullptr);
    if (imageMemory) vkFreeMemory(device, imageMemory, nullptr);
  }
};

void createTarget(const HostVulkan& h, HostTarget& t, uint32_t w, uint32_t hgt) {
  t.device = h.device;
  VkImageCreateInfo ii{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ii.imageType = VK_IMAGE_TYPE_2D;
  ii.format = VK_FORMAT_R8G8B8A8_UNORM;
  ii.extent = {w, hgt, 1};
  ii.mipLevels = ii.arrayLayers = 1;
  ii.samples = VK_SAMPLE_COUNT_1_BIT;
  ii.tiling = VK_IMAGE_TILING_OPTIMAL;
  ii.usage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  HOST_CHECK(vkCreateImage(h.device, &ii, nullptr, &t.image));
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(h.device, t.image, &req);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = memoryType(h.physical, req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  HOST_CHECK(vkAllocateMemory(h.device, &ai, nullptr, &t.imageMemory));
  HOST_CHECK(vkBindImageMemory(h.device, t.image, t.imageMemory, 0));
  VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bi.size = VkDeviceSize(w) * hgt * 4;
  bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  HOST_CHECK(vkCreateBuffer(h.device, &bi, nullptr, &t.readback));
  vkGetBufferMemoryRequirements(h.device, t.readback, &req);
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = memoryType(h.physical, req.memoryTypeBits,
                                  VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
  HOST_CHECK(vkAllocateMemory(h.device, &ai, nullptr, &t.readbackMemory));
  HOST_CHECK(vkBindBufferMemory(h.device, t.readback, t.readbackMemory, 0));
  HOST_CHECK(vkMapMemory(h.device, t.readbackMemory, 0, VK_WHOLE_SIZE, 0, &t.mapped));
}

// Transfer-to-transfer layout changes of the host's own image (visbuf::gpu::imageBarrier takes a raw VkImage).
void imageBarrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to) {
  constexpr VkAccessFlags2 rw = VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_TRANSFER_READ_BIT;
  visbuf::gpu::imageBarrier(cmd, image, from, to, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, rw,
                            VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, rw);
}

visbuf::Camera orbit(const visbuf::Scene& scene, uint32_t frame) {
  visbuf::Camera c = scene.defaultCamera;
  const double a = 0.02 * frame;
  const glm::dvec3 offset = scene.defaultCamera.position - scene.defaultCamera.target;
  const double r = std::hypot(offset.x, offset.z);
  c.position = scene.defaultCamera.target + glm::dvec3(r * std::sin(a), offset.y, r * std::cos(a));
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  uint32_t frames = 90, inFlight = 3, objects = 20000, compare = 0, size = 320;
  bool validation = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](uint32_t lo, uint32_t hi) {
      const long v = i + 1 < argc ? std::strtol(argv[++i], nullptr, 10) : -1;
      if (v < long(lo) || v > long(hi)) {
        std::fprintf(stderr, "host: %s wants a number in [%u, %u]\n", a.c_str(), lo, hi);
        std::exit(2);
      }
      return uint32_t(v);
    };
    if (a == "--frames") frames = value(1, 100000);
    else if (a == "--in-flight") inFlight = value(1, 4);
    else if (a == "--objects") objects = value(1, 10000000);
    else if (a == "--validation") validation = true;
    else if (a == "--compare") compare = value(1, 100);
    else if (a == "--size") size = value(16, 8192);
    else {
      std::fprintf(stderr, "usage: visbuf_host [--frames N] [--in-flight K] [--objects N] [--size W] [--validation] "
                           "[--compare PAIRS]\n");
      return 2;
    }
  }
  HostVulkan host;
  if (!createHostVulkan(host, validation)) return 1;
  auto device = visbuf::gpu::Device::adopt({host.instance, host.physical, host.device, host.queue, host.family});
  if (!device) {
    std::fprintf(stderr, "host: %s\n", device.error().message.c_str());
    return 1;
  }
  auto scene = visbuf::makeFieldScene({.objects = objects});
  if (!scene) return 1;
  const uint32_t w = size, h = size * 3 / 4;
  int rc = 0;
  {
    auto motion = visbuf::SceneMotion::create(*scene, {.moving = 0.05, .churn = 0.0005, .seed = 1});
    if (!motion) return 1;
    auto renderer = visbuf::Renderer::create(
        **device, *scene, {.width = w, .height = h, .framesInFlight = inFlight, .spareObjects = motion->spareObjects()});
    if (!renderer) {
      std::fprintf(stderr, "host: %s\n", renderer.error().message.c_str());
      return 1;
    }
    HostTarget target;
    createTarget(host, target, w, h);
    // The ring: a command buffer and a fence per frame in flight, from the host's own pool.
    VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pci.queueFamilyIndex = host.family;
    VkCommandPool pool;
    HOST_CHECK(vkCreateCommandPool(host.device, &pci, nullptr, &pool));
    std::vector<VkCommandBuffer> cmds(inFlight);
    VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cai.commandPool = pool;
    cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cai.commandBufferCount = inFlight;
    HOST_CHECK(vkAllocateCommandBuffers(host.device, &cai, cmds.data()));
    std::vector<VkFence> fences(inFlight);
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fci.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    for (VkFence& f : fences) HOST_CHECK(vkCreateFence(host.device, &fci, nullptr, &f));

    visbuf::FrameOptions options;
    options.readColor = false;  // record(): the host reads the output images itself
    VkImageLayout targetLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    uint32_t sceneFrame = 0;  // frames of scene changes applied so far (the motion's frame counter)
    // `count` frames through the ring, camera frames first..first+count-1; the last one read back. Seconds.
    auto ring = [&](uint32_t first, uint32_t count, double& gpuMs) -> double {
      double gpuMsSum = 0.0;
      uint32_t completed = 0;
      const auto start = std::chrono::steady_clock::now();
      for (uint32_t i = 0; i < count; ++i) {
        const uint32_t n = first + i, slot = n % inFlight;
        // The only wait: frame n - inFlight, the last user of this slot (and of visbuf's slot n % inFlight).
        HOST_CHECK(vkWaitForFences(host.device, 1, &fences[slot], VK_TRUE, UINT64_MAX));
        if (auto m = motion->apply(**renderer, sceneFrame++); !m) {
          std::fprintf(stderr, "host: scene update: %s\n", m.error().message.c_str());
          std::exit(1);
        }
        auto frame = (*renderer)->record({orbit(*scene, n), options, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL});
        if (!frame) {
          std::fprintf(stderr, "host: %s\n", frame.error().message.c_str());
          std::exit(1);
        }
        if (const auto& done = (*renderer)->completedStats(); done && i >= inFlight) {
          gpuMsSum += done->gpuMs;
          ++completed;
        }
        // The host's commands after visbuf's: compose the colour output into its own image.
        VkCommandBuffer cmd = cmds[slot];
        HOST_CHECK(vkResetCommandBuffer(cmd, 0));
        VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        HOST_CHECK(vkBeginCommandBuffer(cmd, &bi));
        imageBarrier(cmd, target.image, targetLayout, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
        VkImageBlit blit{};
        blit.srcSubresource = blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        blit.srcOffsets[1] = {int32_t(frame->width), int32_t(frame->height), 1};
        blit.dstOffsets[1] = {int32_t(w), int32_t(h), 1};
        vkCmdBlitImage(cmd, frame->color.image, frame->color.layout, target.image,
                       VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_NEAREST);
        imageBarrier(cmd, target.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
        targetLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        if (i + 1 == count) {  // the last frame: read the composed image back
          VkBufferImageCopy region{};
          region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
          region.imageExtent = {w, h, 1};
          vkCmdCopyImageToBuffer(cmd, target.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target.readback, 1, &region);
          visbuf::gpu::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                     VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
        }
        HOST_CHECK(vkEndCommandBuffer(cmd));
        std::vector<VkCommandBufferSubmitInfo> infos;
        for (VkCommandBuffer c : frame->commandBuffers)
          infos.push_back({VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO, nullptr, c, 0});
        infos.push_back({VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO, nullptr, cmd, 0});
        VkSubmitInfo2 submit{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
        submit.commandBufferInfoCount = uint32_t(infos.size());
        submit.pCommandBufferInfos = infos.data();
        HOST_CHECK(vkResetFences(host.device, 1, &fences[slot]));
        HOST_CHECK(vkQueueSubmit2(host.queue, 1, &submit, fences[slot]));
      }
      HOST_CHECK(vkWaitForFences(host.device, inFlight, fences.data(), VK_TRUE, UINT64_MAX));
      gpuMs = completed ? gpuMsSum / completed : 0.0;
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    // The same frames through renderFrame: record, submit, wait, one frame at a time. Seconds.
    auto synchronous = [&](uint32_t first, uint32_t count) -> double {
      const auto start = std::chrono::steady_clock::now();
      for (uint32_t i = 0; i < count; ++i) {
        if (auto m = motion->apply(**renderer, sceneFrame++); !m) std::exit(1);
        if (!(*renderer)->renderFrame(orbit(*scene, first + i), options)) std::exit(1);
      }
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };

    double gpuMs = 0.0;
    const double recordSeconds = ring(0, frames, gpuMs);
    std::printf("host: %u frames recorded with %u in flight: %.1f frames/s (GPU %.3f ms a frame, the mean over the "
                "frames whose stats came back)\n",
                frames, inFlight, frames / recordSeconds, gpuMs);

    // The check: the composed last frame against renderFrame of the same camera and scene.
    visbuf::FrameOptions readBack = options;
    readBack.readColor = true;
    auto ref = (*renderer)->renderFrame(orbit(*scene, frames - 1), readBack);
    if (!ref) {
      std::fprintf(stderr, "host: %s\n", ref.error().message.c_str());
      return 1;
    }
    const auto* px = static_cast<const uint8_t*>(target.mapped);
    double maxDiff = 0.0;
    for (size_t i = 0; i < size_t(w) * h * 4; ++i) {
      const double expect = std::clamp(double(ref->color[i]), 0.0, 1.0);
      maxDiff = std::max(maxDiff, std::abs(px[i] / 255.0 - expect));
    }
    std::printf("host: last frame composed by the host vs renderFrame: max difference %.4f (RGBA8 rounding allows "
                "0.5/255 = %.4f); %u objects drawn\n",
                maxDiff, 0.5 / 255.0, ref->stats.cull.drawsRendered);
    if (maxDiff > 0.5 / 255.0 + 1e-3 || ref->stats.cull.drawsRendered == 0) rc = 1;

    if (compare > 0) {
      // Interleaved pairs (ring block, then renderFrame block over the same cameras): the ratio per pair and its
      // median, so that a noisy machine shows as spread rather than as a bias.
      std::vector<double> ratios;
      for (uint32_t p = 0; p < compare; ++p) {
        double ms = 0.0;
        const double a = ring(0, frames, ms), b = synchronous(0, frames);
        ratios.push_back(b / a);
        std::printf("host: pair %u: record %.1f frames/s, renderFrame %.1f frames/s, ratio %.3f\n", p + 1,
                    frames / a, frames / b, b / a);
      }
      std::vector<double> sorted = ratios;
      std::sort(sorted.begin(), sorted.end());
      std::printf("host: record with %u in flight / renderFrame throughput: median %.3f over %u pairs (min %.3f, max "
                  "%.3f), %u frames each, %u objects at %ux%u\n",
                  inFlight, sorted[sorted.size() / 2], compare, sorted.front(), sorted.back(), frames, objects, w, h);
    }
    for (VkFence f : fences) vkDestroyFence(host.device, f, nullptr);
    vkDestroyCommandPool(host.device, pool, nullptr);
  }
  device->reset();  // visbuf releases its objects before the host destroys the device
  if (g_validationMessages > 0) {
    std::fprintf(stderr, "host: %u validation message(s)\n", g_validationMessages);
    return 3;
  }
  if (rc != 0) std::fprintf(stderr, "host: the composed frame does not match renderFrame\n");
  return rc;
}
