// Shader modules (SPIR-V compiled at build time and embedded), pipelines, descriptor sets and
// timestamp queries.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "visbuf/gpu/device.h"

namespace visbuf::gpu {

// Embedded SPIR-V by file name ("cull.comp", "visibility.vert", ...). Aborts on an unknown name
// (a build error, not user input).
std::span<const uint32_t> shaderCode(const std::string& name);

// Stages that see the shared PassConstants push constants (one range for the whole main layout).
constexpr VkShaderStageFlags kPassConstantStages =
    VK_SHADER_STAGE_COMPUTE_BIT | VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;

// Move-only pipeline owner.
class Pipeline {
 public:
  Pipeline() = default;
  Pipeline(VkDevice device, VkPipeline pipeline) : device_(device), pipeline_(pipeline) {}
  ~Pipeline() { reset(); }
  Pipeline(Pipeline&& o) noexcept { *this = std::move(o); }
  Pipeline& operator=(Pipeline&& o) noexcept;
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;
  void reset();
  VkPipeline handle() const { return pipeline_; }

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
};

// Specialisation constant 0 of every frame shader (common.glsl VB_WINDOWED): 1 when the object records or the
// vertex pool need more than one descriptor window, 0 to read them directly (the windows cost a branch per
// fetch, measurable on lavapipe). Shaders that do not declare it ignore it.
// Specialisation constant 1 (material.glsl VB_TEXTURE_CLASSES): how many baked texture classes the scene has;
// texture sampling code for classes beyond it (all of it for an untextured scene) is removed when the pipeline is
// compiled, which keeps lavapipe's shader compile time and the shaders' size down.
// Specialisation constant 2 (common.glsl VB_SKINNED): 1 when the scene has skinned instances, whose mesh slots
// address skinned vertices (meshVertex()); 0 removes that per-vertex test, so static scenes run the code they
// ran before skinning existed.
// Specialisation constant 3 (common.glsl VB_TEXELS): 1 to read object records, vertex positions and indices through
// uniform texel buffers (GpuScene::texels) in the passes that fetch them per object, triangle or pixel.
// Specialisation constants 4 (common.glsl VB_EXTRAS: a mesh of the scene has VertexExtra records) and 5
// (VB_POINT_LIGHTS: the scene has punctual lights): 0 removes the code that reads them. lavapipe runs both sides of
// every branch under a lane mask, so a branch no pixel takes still costs its loads and arithmetic (a third of the
// shading pass at 10k kittens); both are fixed for a renderer's life (meshes and lights are set at creation).
struct Specialization {
  Specialization(uint32_t windowedValue = 1, uint32_t textureClassCount = 0,  // NOLINT: implicit from `windowed`
                 uint32_t skinnedValue = 0, uint32_t texelsValue = 0)
      : windowed(windowedValue), textureClasses(textureClassCount), skinned(skinnedValue), texels(texelsValue) {}
  uint32_t windowed;
  uint32_t textureClasses;
  uint32_t skinned;
  uint32_t texels;
  uint32_t extras = 1;
  uint32_t pointLights = 1;
  uint32_t materialFeatures = 3;  // MATERIAL_FEATURE_* bits (config.h) the pipeline may meet (constant 6)
};
Pipeline createComputePipeline(Device& device, VkPipelineLayout layout, const std::string& shader,
                               Specialization spec = {});

struct GraphicsPipelineDesc {
  std::string vertexShader;
  std::string fragmentShader;
  std::vector<VkFormat> colorFormats;  // dynamic rendering attachments
  VkFormat depthFormat = VK_FORMAT_D32_SFLOAT;
  VkCullModeFlags cullMode = VK_CULL_MODE_BACK_BIT;
  VkCompareOp depthCompare = VK_COMPARE_OP_GREATER;  // reverse-Z
  bool depthWrite = true;
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;  // rasterisation samples (MSAA targets); no sample shading
  bool premultipliedBlend = false;  // colour = src + (1 - src.a) * dst on every attachment (transparency)
  uint32_t windowed = 1;  // specialisation constant 0 of both stages (see createComputePipeline)
  uint32_t textureClasses = 0;  // specialisation constant 1 of both stages (see Specialization)
  uint32_t skinned = 0;         // specialisation constant 2 of both stages (see Specialization)
  uint32_t texels = 0;          // specialisation constant 3 of both stages (see Specialization)
  uint32_t extras = 1;          // specialisation constant 4 of both stages (see Specialization)
  uint32_t pointLights = 1;     // specialisation constant 5 of both stages (see Specialization)
  uint32_t materialFeatures = 3;  // specialisation constant 6 of both stages (see Specialization)
};
Pipeline createGraphicsPipeline(Device& device, VkPipelineLayout layout, const GraphicsPipelineDesc& desc);

// GPU timestamps: two per named pass, read back after the frame's fence.
class TimestampPool {
 public:
  TimestampPool(Device& device, uint32_t maxPasses);
  ~TimestampPool();
  TimestampPool(const TimestampPool&) = delete;
  TimestampPool& operator=(const TimestampPool&) = delete;
  void reset(VkCommandBuffer cmd);  // at the start of the frame (before any begin)
  // Returns the pass slot; write begin before and end after the pass's commands.
  uint32_t begin(VkCommandBuffer cmd, const std::string& name);
  void end(VkCommandBuffer cmd, uint32_t slot);
  // Milliseconds per pass, in recording order. Call after the frame completed.
  std::vector<std::pair<std::string, double>> read();

 private:
  // lavapipe takes a timestamp when it next flushes its command stream, not where the command stands: a compute pass
  // that nothing flushes in between then measures about 0 ms and its time lands elsewhere (a frame without merges
  // read 150 ms for 430 ms of work). On a CPU device an empty pipeline barrier (which flushes there) follows each
  // timestamp.
  void stampNow(VkCommandBuffer cmd) const;
  Device& device_;
  VkQueryPool pool_ = VK_NULL_HANDLE;
  uint32_t max_;
  std::vector<std::string> names_;
};

}  // namespace visbuf::gpu
