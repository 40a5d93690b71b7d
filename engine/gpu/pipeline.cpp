#include "visbuf/gpu/pipeline.h"

#include <cstdio>
#include <cstdlib>
#include <utility>

#include "visbuf/core/log.h"
#include "visbuf/gpu/check.h"

// Generated at build time by glslangValidator --vn (see shaders/CMakeLists.txt).
#include "cull.comp.h"
#include "cull_clusters.comp.h"
#include "cull_cluster_retest.comp.h"
#include "cull_sieve.comp.h"
#include "cull_occlusion.comp.h"
#include "object_scatter.comp.h"
#include "covered_pixels.comp.h"
#include "clear_ids.comp.h"
#include "clear_ids_wide.comp.h"
#include "shade_covered.comp.h"
#include "shade_covered_textured.comp.h"
#include "shade_resolve.comp.h"
#include "shade_resolve_textured.comp.h"
#include "shade_covered_resolve.comp.h"
#include "shade_covered_resolve_textured.comp.h"
#include "shade_attributes_resolve.comp.h"
#include "shade_attributes_resolve_textured.comp.h"
#include "covered_pixels_resolve.comp.h"
#include "sw_merge.frag.h"
#include "sw_merge.vert.h"
#include "sw_merge_wide.frag.h"
#include "sw_raster.comp.h"
#include "sw_raster_cpu.comp.h"
#include "depth_pyramid.comp.h"
#include "forward.frag.h"
#include "forward_ids.frag.h"
#include "forward_overdraw.frag.h"
#include "visibility_overdraw.frag.h"
#include "visibility_wide_overdraw.frag.h"
#include "forward.vert.h"
#include "gbuffer.frag.h"
#include "gbuffer_lighting.comp.h"
#include "gbuffer_lighting_attributes.comp.h"
#include "gbuffer_overdraw.frag.h"
#include "gbuffer_masked_overdraw.frag.h"
#include "gbuffer_masked_overdraw_textured.frag.h"
#include "gbuffer_masked.frag.h"
#include "gbuffer_masked_textured.frag.h"
#include "gbuffer_textured.frag.h"
#include "gbuffer_overdraw_textured.frag.h"
#include "light_cull.comp.h"
#include "light_cull_msaa.comp.h"
#include "depth_pyramid_msaa.comp.h"
#include "msaa_ids.comp.h"
#include "shade_msaa.comp.h"
#include "shade_msaa_textured.comp.h"
#include "shade.comp.h"
#include "shade_attributes.comp.h"
#include "skin.comp.h"
#include "skin_bounds.comp.h"
#include "visibility.frag.h"
#include "visibility.vert.h"
#include "visibility_wide.frag.h"
#include "visibility_masked.vert.h"
#include "visibility_masked.frag.h"
#include "visibility_masked_wide.frag.h"
#include "visibility_masked_overdraw.frag.h"
#include "visibility_masked_wide_overdraw.frag.h"
#include "forward_masked.frag.h"
#include "forward_masked_ids.frag.h"
#include "forward_masked_overdraw.frag.h"
#include "transparent.frag.h"
#include "visibility_masked_textured.frag.h"
#include "visibility_masked_wide_textured.frag.h"
#include "visibility_masked_overdraw_textured.frag.h"
#include "visibility_masked_wide_overdraw_textured.frag.h"
#include "shade_textured.comp.h"
#include "shade_attributes_textured.comp.h"
#include "forward_textured.frag.h"
#include "forward_ids_textured.frag.h"
#include "forward_overdraw_textured.frag.h"
#include "forward_masked_textured.frag.h"
#include "forward_masked_ids_textured.frag.h"
#include "forward_masked_overdraw_textured.frag.h"
#include "transparent_textured.frag.h"
#include "classify_count.comp.h"
#include "classify_scan.comp.h"
#include "classify_scatter.comp.h"
#include "shade_classified.comp.h"
#include "shade_classified_textured.comp.h"

namespace visbuf::gpu {

namespace {
std::span<const uint32_t> findShader(const std::string& name) {
#define VB_SHADER(file, sym) \
  if (name == file) return {sym, sizeof(sym) / sizeof(uint32_t)};
  VB_SHADER("cull.comp", spv_cull_comp)
  VB_SHADER("cull_clusters.comp", spv_cull_clusters_comp)
  VB_SHADER("cull_cluster_retest.comp", spv_cull_cluster_retest_comp)
  VB_SHADER("cull_sieve.comp", spv_cull_sieve_comp)
  VB_SHADER("cull_occlusion.comp", spv_cull_occlusion_comp)
  VB_SHADER("object_scatter.comp", spv_object_scatter_comp)
  VB_SHADER("sw_raster.comp", spv_sw_raster_comp)
  VB_SHADER("sw_raster_cpu.comp", spv_sw_raster_cpu_comp)
  VB_SHADER("sw_merge.vert", spv_sw_merge_vert)
  VB_SHADER("sw_merge.frag", spv_sw_merge_frag)
  VB_SHADER("sw_merge_wide.frag", spv_sw_merge_wide_frag)
  VB_SHADER("visibility.vert", spv_visibility_vert)
  VB_SHADER("visibility.frag", spv_visibility_frag)
  VB_SHADER("visibility_wide.frag", spv_visibility_wide_frag)
  VB_SHADER("shade.comp", spv_shade_comp)
  VB_SHADER("shade_covered.comp", spv_shade_covered_comp)
  VB_SHADER("shade_covered_textured.comp", spv_shade_covered_textured_comp)
  VB_SHADER("covered_pixels.comp", spv_covered_pixels_comp)
  VB_SHADER("clear_ids.comp", spv_clear_ids_comp)
  VB_SHADER("clear_ids_wide.comp", spv_clear_ids_wide_comp)
  VB_SHADER("shade_resolve.comp", spv_shade_resolve_comp)
  VB_SHADER("shade_resolve_textured.comp", spv_shade_resolve_textured_comp)
  VB_SHADER("shade_covered_resolve.comp", spv_shade_covered_resolve_comp)
  VB_SHADER("shade_covered_resolve_textured.comp", spv_shade_covered_resolve_textured_comp)
  VB_SHADER("shade_attributes_resolve.comp", spv_shade_attributes_resolve_comp)
  VB_SHADER("shade_attributes_resolve_textured.comp", spv_shade_attributes_resolve_textured_comp)
  VB_SHADER("covered_pixels_resolve.comp", spv_covered_pixels_resolve_comp)
  VB_SHADER("shade_attributes.comp", spv_shade_attributes_comp)
  VB_SHADER("skin.comp", spv_skin_comp)
  VB_SHADER("skin_bounds.comp", spv_skin_bounds_comp)
  VB_SHADER("light_cull.comp", spv_light_cull_comp)
  VB_SHADER("light_cull_msaa.comp", spv_light_cull_msaa_comp)
  VB_SHADER("depth_pyramid_msaa.comp", spv_depth_pyramid_msaa_comp)
  VB_SHADER("msaa_ids.comp", spv_msaa_ids_comp)
  VB_SHADER("shade_msaa.comp", spv_shade_msaa_comp)
  VB_SHADER("shade_msaa_textured.comp", spv_shade_msaa_textured_comp)
  VB_SHADER("depth_pyramid.comp", spv_depth_pyramid_comp)
  VB_SHADER("forward.vert", spv_forward_vert)
  VB_SHADER("forward.frag", spv_forward_frag)
  VB_SHADER("forward_ids.frag", spv_forward_ids_frag)
  VB_SHADER("forward_overdraw.frag", spv_forward_overdraw_frag)
  VB_SHADER("visibility_overdraw.frag", spv_visibility_overdraw_frag)
  VB_SHADER("visibility_wide_overdraw.frag", spv_visibility_wide_overdraw_frag)
  VB_SHADER("visibility_masked.vert", spv_visibility_masked_vert)
  VB_SHADER("visibility_masked.frag", spv_visibility_masked_frag)
  VB_SHADER("visibility_masked_wide.frag", spv_visibility_masked_wide_frag)
  VB_SHADER("visibility_masked_overdraw.frag", spv_visibility_masked_overdraw_frag)
  VB_SHADER("visibility_masked_wide_overdraw.frag", spv_visibility_masked_wide_overdraw_frag)
  VB_SHADER("forward_masked.frag", spv_forward_masked_frag)
  VB_SHADER("forward_masked_ids.frag", spv_forward_masked_ids_frag)
  VB_SHADER("forward_masked_overdraw.frag", spv_forward_masked_overdraw_frag)
  VB_SHADER("transparent.frag", spv_transparent_frag)
  VB_SHADER("visibility_masked_textured.frag", spv_visibility_masked_textured_frag)
  VB_SHADER("visibility_masked_wide_textured.frag", spv_visibility_masked_wide_textured_frag)
  VB_SHADER("visibility_masked_overdraw_textured.frag", spv_visibility_masked_overdraw_textured_frag)
  VB_SHADER("visibility_masked_wide_overdraw_textured.frag", spv_visibility_masked_wide_overdraw_textured_frag)
  VB_SHADER("shade_textured.comp", spv_shade_textured_comp)
  VB_SHADER("shade_attributes_textured.comp", spv_shade_attributes_textured_comp)
  VB_SHADER("forward_textured.frag", spv_forward_textured_frag)
  VB_SHADER("forward_ids_textured.frag", spv_forward_ids_textured_frag)
  VB_SHADER("forward_overdraw_textured.frag", spv_forward_overdraw_textured_frag)
  VB_SHADER("forward_masked_textured.frag", spv_forward_masked_textured_frag)
  VB_SHADER("forward_masked_ids_textured.frag", spv_forward_masked_ids_textured_frag)
  VB_SHADER("forward_masked_overdraw_textured.frag", spv_forward_masked_overdraw_textured_frag)
  VB_SHADER("transparent_textured.frag", spv_transparent_textured_frag)
  VB_SHADER("gbuffer.frag", spv_gbuffer_frag)
  VB_SHADER("gbuffer_textured.frag", spv_gbuffer_textured_frag)
  VB_SHADER("gbuffer_overdraw.frag", spv_gbuffer_overdraw_frag)
  VB_SHADER("gbuffer_masked_overdraw.frag", spv_gbuffer_masked_overdraw_frag)
  VB_SHADER("gbuffer_masked_overdraw_textured.frag", spv_gbuffer_masked_overdraw_textured_frag)
  VB_SHADER("gbuffer_masked.frag", spv_gbuffer_masked_frag)
  VB_SHADER("gbuffer_masked_textured.frag", spv_gbuffer_masked_textured_frag)
  VB_SHADER("gbuffer_overdraw_textured.frag", spv_gbuffer_overdraw_textured_frag)
  VB_SHADER("gbuffer_lighting.comp", spv_gbuffer_lighting_comp)
  VB_SHADER("gbuffer_lighting_attributes.comp", spv_gbuffer_lighting_attributes_comp)
  VB_SHADER("classify_count.comp", spv_classify_count_comp)
  VB_SHADER("classify_scan.comp", spv_classify_scan_comp)
  VB_SHADER("classify_scatter.comp", spv_classify_scatter_comp)
  VB_SHADER("shade_classified.comp", spv_shade_classified_comp)
  VB_SHADER("shade_classified_textured.comp", spv_shade_classified_textured_comp)
#undef VB_SHADER
  return {};
}
}  // namespace

std::span<const uint32_t> shaderCode(const std::string& name) {
  std::span<const uint32_t> code = findShader(name);
  if (code.empty()) {
    logMessage(LogLevel::Error, "fatal: no embedded shader named '" + name + "'");  // a build error
    std::abort();
  }
  return code;
}

namespace {
// textured: the NAME_textured.STAGE variant where the shader has one (material shaders, shaders/CMakeLists.txt).
VkShaderModule createModule(Device& device, const std::string& name, bool textured) {
  std::span<const uint32_t> code;
  if (textured) code = findShader(name.substr(0, name.rfind('.')) + "_textured" + name.substr(name.rfind('.')));
  if (code.empty()) code = shaderCode(name);
  VkShaderModuleCreateInfo ci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  ci.codeSize = code.size_bytes();
  ci.pCode = code.data();
  VkShaderModule module;
  VK_CHECK(vkCreateShaderModule(device.device(), &ci, nullptr, &module));
  return module;
}

// A shader module destroyed when it goes out of scope: also when the pipeline's creation fails.
struct ModuleOwner {
  VkDevice device;
  VkShaderModule module;
  ModuleOwner(Device& d, const std::string& name, bool textured)
      : device(d.device()), module(createModule(d, name, textured)) {}
  ~ModuleOwner() { vkDestroyShaderModule(device, module, nullptr); }
  ModuleOwner(const ModuleOwner&) = delete;
  ModuleOwner& operator=(const ModuleOwner&) = delete;
};
}  // namespace

Pipeline& Pipeline::operator=(Pipeline&& o) noexcept {
  if (this != &o) {
    reset();
    device_ = std::exchange(o.device_, VK_NULL_HANDLE);
    pipeline_ = std::exchange(o.pipeline_, VK_NULL_HANDLE);
  }
  return *this;
}

void Pipeline::reset() {
  if (pipeline_) vkDestroyPipeline(device_, pipeline_, nullptr);
  pipeline_ = VK_NULL_HANDLE;
}

namespace {
const VkSpecializationMapEntry kEntries[7] = {
    {0, 0, sizeof(uint32_t)},     {1, sizeof(uint32_t), sizeof(uint32_t)}, {2, 2 * sizeof(uint32_t), sizeof(uint32_t)},
    {3, 3 * sizeof(uint32_t), 4}, {4, 4 * sizeof(uint32_t), 4},           {5, 5 * sizeof(uint32_t), 4},
    {6, 6 * sizeof(uint32_t), 4}};
VkSpecializationInfo specializationInfo(const uint32_t (&values)[7]) { return {7, kEntries, sizeof(values), values}; }
}  // namespace

Pipeline createComputePipeline(Device& device, VkPipelineLayout layout, const std::string& shader,
                               Specialization specialization) {
  const ModuleOwner module(device, shader, specialization.textureClasses > 0);
  const uint32_t values[7] = {specialization.windowed, specialization.textureClasses, specialization.skinned,
                              specialization.texels,   specialization.extras,         specialization.pointLights,
                              specialization.materialFeatures};
  const VkSpecializationInfo spec = specializationInfo(values);
  VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  ci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = module.module;
  ci.stage.pName = "main";
  ci.stage.pSpecializationInfo = &spec;
  ci.layout = layout;
  VkPipeline pipeline;
  VK_CHECK(vkCreateComputePipelines(device.device(), VK_NULL_HANDLE, 1, &ci, nullptr, &pipeline));
  return Pipeline(device.device(), pipeline);
}

Pipeline createGraphicsPipeline(Device& device, VkPipelineLayout layout, const GraphicsPipelineDesc& desc) {
  const ModuleOwner vs(device, desc.vertexShader, desc.textureClasses > 0);
  const ModuleOwner fs(device, desc.fragmentShader, desc.textureClasses > 0);
  VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
                                               {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = vs.module;
  stages[0].pName = "main";
  stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
  stages[1].module = fs.module;
  stages[1].pName = "main";
  const uint32_t values[7] = {desc.windowed, desc.textureClasses, desc.skinned,         desc.texels,
                              desc.extras,   desc.pointLights,    desc.materialFeatures};
  const VkSpecializationInfo spec = specializationInfo(values);
  stages[0].pSpecializationInfo = stages[1].pSpecializationInfo = &spec;

  VkPipelineVertexInputStateCreateInfo vi{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};  // pulled
  VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  vp.viewportCount = 1;
  vp.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  rs.polygonMode = VK_POLYGON_MODE_FILL;
  rs.cullMode = desc.cullMode;
  rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  rs.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  ms.rasterizationSamples = desc.samples;
  VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  ds.depthTestEnable = VK_TRUE;
  ds.depthWriteEnable = desc.depthWrite ? VK_TRUE : VK_FALSE;
  ds.depthCompareOp = desc.depthCompare;
  std::vector<VkPipelineColorBlendAttachmentState> blends(desc.colorFormats.size());
  for (auto& b : blends) {
    b.colorWriteMask = 0xF;
    if (desc.premultipliedBlend) {  // out = src + (1 - src.a) * dst
      b.blendEnable = VK_TRUE;
      b.srcColorBlendFactor = b.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
      b.dstColorBlendFactor = b.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
      b.colorBlendOp = b.alphaBlendOp = VK_BLEND_OP_ADD;
    }
  }
  VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  cb.attachmentCount = static_cast<uint32_t>(blends.size());
  cb.pAttachments = blends.data();
  VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  VkPipelineDynamicStateCreateInfo dy{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dy.dynamicStateCount = 2;
  dy.pDynamicStates = dyn;
  VkPipelineRenderingCreateInfo ri{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
  ri.colorAttachmentCount = static_cast<uint32_t>(desc.colorFormats.size());
  ri.pColorAttachmentFormats = desc.colorFormats.data();
  ri.depthAttachmentFormat = desc.depthFormat;

  VkGraphicsPipelineCreateInfo ci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  ci.pNext = &ri;
  ci.stageCount = 2;
  ci.pStages = stages;
  ci.pVertexInputState = &vi;
  ci.pInputAssemblyState = &ia;
  ci.pViewportState = &vp;
  ci.pRasterizationState = &rs;
  ci.pMultisampleState = &ms;
  ci.pDepthStencilState = &ds;
  ci.pColorBlendState = &cb;
  ci.pDynamicState = &dy;
  ci.layout = layout;
  VkPipeline pipeline;
  VK_CHECK(vkCreateGraphicsPipelines(device.device(), VK_NULL_HANDLE, 1, &ci, nullptr, &pipeline));
  return Pipeline(device.device(), pipeline);
}

TimestampPool::TimestampPool(Device& device, uint32_t maxPasses) : device_(device), max_(maxPasses) {
  VkQueryPoolCreateInfo ci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  ci.queryType = VK_QUERY_TYPE_TIMESTAMP;
  ci.queryCount = maxPasses * 2;
  VK_CHECK(vkCreateQueryPool(device.device(), &ci, nullptr, &pool_));
}

TimestampPool::~TimestampPool() { vkDestroyQueryPool(device_.device(), pool_, nullptr); }

void TimestampPool::reset(VkCommandBuffer cmd) {
  vkCmdResetQueryPool(cmd, pool_, 0, max_ * 2);
  names_.clear();
}

uint32_t TimestampPool::begin(VkCommandBuffer cmd, const std::string& name) {
  uint32_t slot = static_cast<uint32_t>(names_.size());
  if (slot >= max_) vkCheckFailed("TimestampPool::begin (too many passes)", VK_ERROR_TOO_MANY_OBJECTS, __FILE__, __LINE__);
  names_.push_back(name);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool_, slot * 2);
  stampNow(cmd);
  return slot;
}

void TimestampPool::end(VkCommandBuffer cmd, uint32_t slot) {
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool_, slot * 2 + 1);
  stampNow(cmd);
}

void TimestampPool::stampNow(VkCommandBuffer cmd) const {
  if (!device_.isCpu()) return;
  VkDependencyInfo none{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};  // (no barrier: lavapipe flushes on any)
  vkCmdPipelineBarrier2(cmd, &none);
}

std::vector<std::pair<std::string, double>> TimestampPool::read() {
  std::vector<std::pair<std::string, double>> out;
  if (names_.empty()) return out;
  std::vector<uint64_t> ticks(names_.size() * 2);
  VK_CHECK(vkGetQueryPoolResults(device_.device(), pool_, 0, static_cast<uint32_t>(ticks.size()),
                                 ticks.size() * sizeof(uint64_t), ticks.data(), sizeof(uint64_t),
                                 VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  for (size_t i = 0; i < names_.size(); ++i) {
    double ms = double(ticks[2 * i + 1] - ticks[2 * i]) * device_.timestampPeriodNs() * 1e-6;
    out.emplace_back(names_[i], ms);
  }
  return out;
}

}  // namespace visbuf::gpu
