// `visbuf render`'s memory estimate: host and device bytes for --objects, --lights, --materials and
// the frame's targets, checked against what the machine and the device have before anything is allocated.
// The per-object and per-pixel sizes are those of the engine's own structures (engine/scene/gpu_scene.cpp,
// engine/render/renderer.cpp). It estimates the bytes allocated (address space, what `ulimit -v` and a GPU heap
// bound), not what becomes resident: lavapipe commits pages only as they are touched.
#pragma once

#include <cstdint>
#include <string>

#include "visbuf/core/result.h"
#include "visbuf/gpu/device.h"
#include "visbuf/scene/scene.h"

namespace visbuf::tools {

struct MemoryEstimate {
  uint64_t host = 0;    // system memory: the scene, its CPU-side GPU records, staging copies, read-backs
  uint64_t device = 0;  // device memory: GPU buffers and images
  std::string hostDetail, deviceDetail;  // "objects 30.5 GiB (320 bytes each), ..." for the message
};

struct RenderBudgetInput {
  uint64_t objects = 0;    // objects the scene will have (0: unknown / the layout's small default)
  uint64_t lights = 0;
  uint64_t materials = 0;
  uint32_t width = 0, height = 0;
  uint32_t msaa = 1;
  bool gbuffer = false;    // --path gbuffer: the G-buffer targets
  bool ids = false;        // --ids-out: the ID image is read back
  bool reference = false;  // a second frame's colour is kept for the comparison
  bool debugView = false;  // --view other than shaded: one more colour image on the host
};

// Before the scene exists: what --objects etc. and the targets will need.
MemoryEstimate estimateRender(const RenderBudgetInput& in);
// Once the scene is loaded (its host memory spent): what uploading it and the targets will need on the device.
MemoryEstimate estimateUpload(const Scene& scene, const RenderBudgetInput& in);

// CapacityExceeded, naming `what` (the options that asked for it), when the estimate exceeds the host memory
// this process can still allocate (availableHostMemory) or the device's memory (the largest DEVICE_LOCAL heap
// of VkPhysicalDeviceMemoryProperties). On a CPU device (lavapipe) device memory is host memory: the sum must
// fit the host, and the heap's nominal size (lavapipe: 2 GiB, allocated beyond) is not a bound. `device` may
// be null (host only).
Status checkMemory(const MemoryEstimate& estimate, const gpu::Device* device, const std::string& what);

}  // namespace visbuf::tools
