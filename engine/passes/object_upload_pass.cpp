#include "visbuf/passes/object_upload_pass.h"

#include "visbuf/gpu/check.h"

namespace visbuf::passes {

namespace {
struct ScatterConstants {  // object_scatter.comp.glsl Push
  VkDeviceAddress records;
  VkDeviceAddress ids;
  VkDeviceAddress objects;
  uint32_t count;
  uint32_t pad;
};
}  // namespace

ObjectUploadPass::~ObjectUploadPass() {
  pipeline_.reset();
  if (layout_) vkDestroyPipelineLayout(device_, layout_, nullptr);
}

void ObjectUploadPass::create(gpu::Device& device) {
  device_ = device.device();
  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(ScatterConstants)};
  VkPipelineLayoutCreateInfo pci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pci.pushConstantRangeCount = 1;
  pci.pPushConstantRanges = &range;
  VK_CHECK(vkCreatePipelineLayout(device_, &pci, nullptr, &layout_));
  pipeline_ = gpu::createComputePipeline(device, layout_, "object_scatter.comp");
}

void ObjectUploadPass::record(VkCommandBuffer cmd, const gpu::Buffer& staging, VkDeviceSize idsOffset,
                              const gpu::Buffer& objects, uint32_t count) const {
  const ScatterConstants c{staging.address(), staging.address() + idsOffset, objects.address(), count, 0};
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_.handle());
  vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(c), &c);
  vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
}

}  // namespace visbuf::passes
